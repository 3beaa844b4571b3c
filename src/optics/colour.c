/* CIELAB colour of linear-sRGB albedos and the CIEDE2000 colour difference
 * (seed 003 §5.2 colours; used by `skinsim optics match`, the swatch and the
 * skin-tone tests).
 *
 * - Linear sRGB (IEC 61966-2-1 primaries, D65) -> XYZ with the standard
 *   matrix; white (1,1,1) -> the D65 white point Xn, Yn, Zn = (0.95047, 1,
 *   1.08883), so skinsim's white-normalised albedos map to L* = 100, a* = b* = 0.
 * - CIELAB (CIE 15:2004) with the usual cube root and linear segment below
 *   (6/29)^3.
 * - CIEDE2000 (CIE 142-2001) with kL = kC = kH = 1, implemented after Sharma,
 *   Wu & Dalal 2005 (Color Res. Appl. 30:21), whose 34 test pairs are the unit
 *   test; hue means and differences follow their equations (10)-(16).
 * - C*ab = sqrt(a^2 + b^2), h_ab = atan2(b, a) in degrees [0, 360), and the
 *   individual typology angle ITA = atan((L* - 50) / b*) in degrees
 *   (Chardon, Cretois & Hourseau 1991), computed with atan2 so b* <= 0 gives
 *   +-90 degrees. */
#include <math.h>

#include "skinsim/optics.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const double SRGB_TO_XYZ[3][3] = {{0.4124564, 0.3575761, 0.1804375},
                                         {0.2126729, 0.7151522, 0.0721750},
                                         {0.0193339, 0.1191920, 0.9503041}};

static double lab_f(double t) {
    const double d = 6.0 / 29.0;
    return t > d * d * d ? cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
}
static double lab_finv(double f) {
    const double d = 6.0 / 29.0;
    return f > d ? f * f * f : 3.0 * d * d * (f - 4.0 / 29.0);
}

static void white_xyz(double w[3]) {
    for (int r = 0; r < 3; r++) w[r] = SRGB_TO_XYZ[r][0] + SRGB_TO_XYZ[r][1] + SRGB_TO_XYZ[r][2];
}

void ss_srgb_linear_to_lab(const double rgb[3], double lab[3]) {
    double xyz[3], w[3];
    white_xyz(w);
    for (int r = 0; r < 3; r++)
        xyz[r] =
            SRGB_TO_XYZ[r][0] * rgb[0] + SRGB_TO_XYZ[r][1] * rgb[1] + SRGB_TO_XYZ[r][2] * rgb[2];
    double fx = lab_f(xyz[0] / w[0]), fy = lab_f(xyz[1] / w[1]), fz = lab_f(xyz[2] / w[2]);
    lab[0] = 116.0 * fy - 16.0;
    lab[1] = 500.0 * (fx - fy);
    lab[2] = 200.0 * (fy - fz);
}

void ss_lab_to_srgb_linear(const double lab[3], double rgb[3]) {
    double w[3];
    white_xyz(w);
    double fy = (lab[0] + 16.0) / 116.0, fx = fy + lab[1] / 500.0, fz = fy - lab[2] / 200.0;
    double xyz[3] = {w[0] * lab_finv(fx), w[1] * lab_finv(fy), w[2] * lab_finv(fz)};
    /* exact inverse of SRGB_TO_XYZ (adjugate / determinant), so round trips close */
    const double(*m)[3] = SRGB_TO_XYZ;
    double inv[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
            inv[r][c] = m[r1][c1] * m[r2][c2] - m[r1][c2] * m[r2][c1];
        }
    double det = m[0][0] * inv[0][0] + m[0][1] * inv[1][0] + m[0][2] * inv[2][0];
    for (int r = 0; r < 3; r++)
        rgb[r] = (inv[r][0] * xyz[0] + inv[r][1] * xyz[1] + inv[r][2] * xyz[2]) / det;
}

void ss_lab_describe(const double lab[3], double *chroma, double *hue_deg, double *ita_deg) {
    if (chroma) *chroma = hypot(lab[1], lab[2]);
    if (hue_deg) {
        double h = atan2(lab[2], lab[1]) * 180.0 / M_PI;
        *hue_deg = h < 0.0 ? h + 360.0 : h;
    }
    if (ita_deg) *ita_deg = atan2(lab[0] - 50.0, lab[2]) * 180.0 / M_PI;
}

double ss_ciede2000(const double lab1[3], const double lab2[3]) {
    const double L1 = lab1[0], a1 = lab1[1], b1 = lab1[2];
    const double L2 = lab2[0], a2 = lab2[1], b2 = lab2[2];
    const double deg = M_PI / 180.0;
    double C1 = hypot(a1, b1), C2 = hypot(a2, b2), Cb = 0.5 * (C1 + C2);
    double Cb7 = pow(Cb, 7.0);
    double G = 0.5 * (1.0 - sqrt(Cb7 / (Cb7 + pow(25.0, 7.0))));
    double a1p = (1.0 + G) * a1, a2p = (1.0 + G) * a2;
    double C1p = hypot(a1p, b1), C2p = hypot(a2p, b2);
    double h1p = (a1p == 0.0 && b1 == 0.0) ? 0.0 : atan2(b1, a1p) / deg;
    double h2p = (a2p == 0.0 && b2 == 0.0) ? 0.0 : atan2(b2, a2p) / deg;
    if (h1p < 0.0) h1p += 360.0;
    if (h2p < 0.0) h2p += 360.0;
    double dLp = L2 - L1, dCp = C2p - C1p, dhp;
    if (C1p * C2p == 0.0)
        dhp = 0.0;
    else {
        dhp = h2p - h1p;
        if (dhp > 180.0)
            dhp -= 360.0;
        else if (dhp < -180.0)
            dhp += 360.0;
    }
    double dHp = 2.0 * sqrt(C1p * C2p) * sin(0.5 * dhp * deg);
    double Lbp = 0.5 * (L1 + L2), Cbp = 0.5 * (C1p + C2p), hbp;
    if (C1p * C2p == 0.0)
        hbp = h1p + h2p;
    else if (fabs(h1p - h2p) <= 180.0)
        hbp = 0.5 * (h1p + h2p);
    else if (h1p + h2p < 360.0)
        hbp = 0.5 * (h1p + h2p + 360.0);
    else
        hbp = 0.5 * (h1p + h2p - 360.0);
    double T = 1.0 - 0.17 * cos((hbp - 30.0) * deg) + 0.24 * cos(2.0 * hbp * deg) +
               0.32 * cos((3.0 * hbp + 6.0) * deg) - 0.20 * cos((4.0 * hbp - 63.0) * deg);
    double dth = 30.0 * exp(-((hbp - 275.0) / 25.0) * ((hbp - 275.0) / 25.0));
    double Cbp7 = pow(Cbp, 7.0);
    double RC = 2.0 * sqrt(Cbp7 / (Cbp7 + pow(25.0, 7.0)));
    double l50 = (Lbp - 50.0) * (Lbp - 50.0);
    double SL = 1.0 + 0.015 * l50 / sqrt(20.0 + l50);
    double SC = 1.0 + 0.045 * Cbp, SH = 1.0 + 0.015 * Cbp * T;
    double RT = -sin(2.0 * dth * deg) * RC;
    double tL = dLp / SL, tC = dCp / SC, tH = dHp / SH;
    return sqrt(tL * tL + tC * tC + tH * tH + RT * tC * tH);
}
