/* Example: the reflectance spectrum and colour of one skin, with the
 * installed library.
 *
 *   cc skin_colour.c $(pkg-config --cflags --libs skinsim) -o skin_colour
 *   ./skin_colour 0.08 0.02          # melanin fraction, blood fraction
 *   ./skin_colour 0.08 0.02 50000    # more photons per wavelength, less noise
 *
 * Prints the diffuse reflectance every 50 nm, the linear sRGB albedo and the
 * 8-bit sRGB colour. Bad values are refused with the library's message. */
#include <stdio.h>
#include <stdlib.h>

#include <skinsim/core.h>
#include <skinsim/optics.h>

int main(int argc, char **argv) {
    ss_bio_params bio;
    ss_bio_params_default(&bio);
    if (argc > 1) bio.melanin = atof(argv[1]);
    if (argc > 2) bio.blood = atof(argv[2]);

    ss_spectrum_options opt;
    ss_spectrum_options_default(&opt); /* 380..780 nm every 10 nm */
    opt.mc.photons = 5000;             /* per wavelength: quick, a few % noise */
    if (argc > 3) opt.mc.photons = (uint64_t)strtoull(argv[3], NULL, 10);

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
