/* Example: the reflectance spectrum and colour of one skin, with the
 * installed library.
 *
 *   cc skin_colour.c $(pkg-config --cflags --libs skinsim) -o skin_colour
 *   ./skin_colour 0.08 0.02          # melanin fraction, blood fraction
 *   ./skin_colour 0.08 0.02 50000    # more photons per wavelength, less noise
 *
 * Prints the diffuse reflectance every 50 nm, the linear sRGB albedo and the
 * 8-bit sRGB colour. An argument that is not a number is refused (exit 2);
 * bad values are refused with the library's message (exit 2). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

#include <skinsim/core.h>
#include <skinsim/optics.h>

/* The whole of text as a finite number, else a message naming what and exit 2. */
static double number_arg(const char *text, const char *what) {
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || v != v) {
        fprintf(stderr, "skin_colour: %s '%s' is not a number\n", what, text);
        exit(2);
    }
    return v;
}

int main(int argc, char **argv) {
    if (argc > 4) {
        fprintf(stderr, "usage: skin_colour [MELANIN [BLOOD [PHOTONS]]]\n");
        return 2;
    }
    ss_bio_params bio;
    ss_bio_params_default(&bio);
    if (argc > 1) bio.melanin = number_arg(argv[1], "melanin");
    if (argc > 2) bio.blood = number_arg(argv[2], "blood");

    ss_spectrum_options opt;
    ss_spectrum_options_default(&opt); /* 380..780 nm every 10 nm */
    opt.mc.photons = 5000;             /* per wavelength: quick, a few % noise */
    if (argc > 3) {
        double ph = number_arg(argv[3], "photons");
        if (ph < 1 || ph > 1e12 || ph != (double)(uint64_t)ph) {
            fprintf(stderr, "skin_colour: photons '%s': want a whole number in 1..1e12\n", argv[3]);
            return 2;
        }
        opt.mc.photons = (uint64_t)ph;
    }

    ss_error err = {0};
    ss_reflectance_spectrum spec = {0};
    double rgb[3];
    ss_status st = ss_optics_reflectance_spectrum(&bio, &opt, &spec, &err);
    if (!st)
        st = ss_spectrum_to_srgb_linear(spec.wavelength_nm, spec.reflectance, spec.n, rgb, &err);
    if (st) {
        fprintf(stderr, "skin_colour: %s\n", err.msg);
        return ss_status_exit_code(st);
    }
    printf("skinsim %s, data in %s\n", ss_version(), ss_data_dir());
    printf("melanin %.3f, blood %.3f\n", bio.melanin, bio.blood);
    for (int i = 0; i < spec.n; i++)
        if ((int)spec.wavelength_nm[i] % 50 == 0)
            printf("  %3.0f nm  R = %.3f\n", spec.wavelength_nm[i], spec.reflectance[i]);
    printf("linear sRGB albedo %.4f %.4f %.4f\n", rgb[0], rgb[1], rgb[2]);
    printf("sRGB #%02x%02x%02x\n", (int)(255 * ss_srgb_encode((float)rgb[0]) + 0.5f),
           (int)(255 * ss_srgb_encode((float)rgb[1]) + 0.5f),
           (int)(255 * ss_srgb_encode((float)rgb[2]) + 0.5f));
    ss_reflectance_spectrum_free(&spec);
    return 0;
}
