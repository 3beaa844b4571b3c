/* Colour differences for the wound checks: linear sRGB (D65) -> CIE XYZ (IEC
 * 61966-2-1 matrix) -> CIELAB with the D65 white, and the CIEDE2000 colour
 * difference exactly as Sharma, Wu & Dalal (2005, Color Res. Appl. 30: 21-30)
 * give it, including their notes on the hue mean and difference; the test
 * checks it against their published test pairs. */
#include <math.h>

#include "skinsim/wound.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double lab_f(double t) {
    const double d = 6.0 / 29.0;
    return t > d * d * d ? cbrt(t) : t / (3 * d * d) + 4.0 / 29.0;
}

void ss_linear_srgb_to_lab(const double rgb[3], double lab[3]) {
    double X = 0.4124564 * rgb[0] + 0.3575761 * rgb[1] + 0.1804375 * rgb[2];
    double Y = 0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2];
    double Z = 0.0193339 * rgb[0] + 0.1191920 * rgb[1] + 0.9503041 * rgb[2];
    double fx = lab_f(X / 0.95047), fy = lab_f(Y / 1.0), fz = lab_f(Z / 1.08883);
    lab[0] = 116 * fy - 16;
    lab[1] = 500 * (fx - fy);
    lab[2] = 200 * (fy - fz);
}

static double deg(double rad) { return rad * 180.0 / M_PI; }
static double rad(double d) { return d * M_PI / 180.0; }

double ss_delta_e2000(const double lab1[3], const double lab2[3]) {
    double L1 = lab1[0], a1 = lab1[1], b1 = lab1[2], L2 = lab2[0], a2 = lab2[1], b2 = lab2[2];
    double C1 = hypot(a1, b1), C2 = hypot(a2, b2), Cm = 0.5 * (C1 + C2);
    double Cm7 = pow(Cm, 7), G = 0.5 * (1 - sqrt(Cm7 / (Cm7 + pow(25, 7))));
    double a1p = (1 + G) * a1, a2p = (1 + G) * a2;
    double C1p = hypot(a1p, b1), C2p = hypot(a2p, b2);
    double h1p = (a1p == 0 && b1 == 0) ? 0 : deg(atan2(b1, a1p));
    double h2p = (a2p == 0 && b2 == 0) ? 0 : deg(atan2(b2, a2p));
    if (h1p < 0) h1p += 360;
    if (h2p < 0) h2p += 360;
    double dLp = L2 - L1, dCp = C2p - C1p, dhp = 0;
    if (C1p * C2p != 0) {
        dhp = h2p - h1p;
        if (dhp > 180)
            dhp -= 360;
        else if (dhp < -180)
            dhp += 360;
    }
    double dHp = 2 * sqrt(C1p * C2p) * sin(rad(dhp / 2));
    double Lpm = 0.5 * (L1 + L2), Cpm = 0.5 * (C1p + C2p), hpm = h1p + h2p;
    if (C1p * C2p != 0) {
        if (fabs(h1p - h2p) <= 180)
            hpm = 0.5 * (h1p + h2p);
        else
            hpm = (h1p + h2p < 360) ? 0.5 * (h1p + h2p + 360) : 0.5 * (h1p + h2p - 360);
    }
    double T = 1 - 0.17 * cos(rad(hpm - 30)) + 0.24 * cos(rad(2 * hpm)) +
               0.32 * cos(rad(3 * hpm + 6)) - 0.20 * cos(rad(4 * hpm - 63));
    double dtheta = 30 * exp(-pow((hpm - 275) / 25, 2));
    double Cpm7 = pow(Cpm, 7), RC = 2 * sqrt(Cpm7 / (Cpm7 + pow(25, 7)));
    double Lm50 = (Lpm - 50) * (Lpm - 50);
    double SL = 1 + 0.015 * Lm50 / sqrt(20 + Lm50), SC = 1 + 0.045 * Cpm, SH = 1 + 0.015 * Cpm * T;
    double RT = -sin(rad(2 * dtheta)) * RC;
    double l = dLp / SL, c = dCp / SC, h = dHp / SH;
    return sqrt(l * l + c * c + h * h + RT * c * h);
}
