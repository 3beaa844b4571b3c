/* Seeds for the fuzz targets: `make_seeds DIR SRC` writes DIR/<target>/<name>
 * for every format, valid inputs made with the library's own writers (so they
 * carry right checksums and layouts), the shipped data files, and the
 * hostile cases of issue 7 (a PNG header bomb, an id of 2^31-1, 1e-320,
 * outputs leaving an .mci's folder, absurd sizes in sealed files). */
#define _GNU_SOURCE
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

#include "skinsim/core.h"
#include "skinsim/geom.h"
#include "skinsim/heal.h"
#include "skinsim/heal_io.h"
#include "skinsim/optics_fit.h"

static const char *root;

static char *target_path(const char *target, const char *name) {
    char *p = NULL;
    if (asprintf(&p, "%s/%s", root, target) < 0) exit(1);
    mkdir(p, 0755);
    free(p);
    if (asprintf(&p, "%s/%s/%s", root, target, name) < 0) exit(1);
    return p;
}

static void seed(const char *target, const char *name, const void *data, size_t len) {
    char *p = target_path(target, name);
    FILE *f = fopen(p, "wb");
    if (!f || fwrite(data, 1, len, f) != len) {
        fprintf(stderr, "make_seeds: cannot write %s\n", p);
        exit(1);
    }
    fclose(f);
    free(p);
}

static void seed_text(const char *target, const char *name, const char *text) {
    seed(target, name, text, strlen(text));
}

static char *slurp(const char *path, size_t *len) {
    ss_error err;
    char *t = ss_read_file(path, len, &err);
    if (!t) {
        fprintf(stderr, "make_seeds: %s\n", err.msg);
        exit(1);
    }
    return t;
}

static void seed_copy(const char *target, const char *name, const char *path, int prefix_byte) {
    size_t len;
    char *t = slurp(path, &len);
    if (prefix_byte >= 0) {
        char *q = malloc(len + 1);
        q[0] = (char)prefix_byte;
        memcpy(q + 1, t, len);
        seed(target, name, q, len + 1);
        free(q);
    } else {
        seed(target, name, t, len);
    }
    free(t);
}

/* A copy of a library-written file with its trailing CRC re-made after an edit. */
static void reseal(char *buf, size_t len) {
    uint32_t c = (uint32_t)crc32_z(crc32_z(0L, Z_NULL, 0), (const Bytef *)buf, len - 4);
    for (int k = 0; k < 4; k++) buf[len - 4 + k] = (char)(c >> (8 * k));
}

static void png_chunk(FILE *f, const char *type, const unsigned char *d, unsigned n) {
    unsigned char h[8] = {n >> 24, n >> 16, n >> 8, n, 0, 0, 0, 0};
    memcpy(h + 4, type, 4);
    fwrite(h, 1, 8, f);
    if (n) fwrite(d, 1, n, f);
    uLong c = crc32(crc32(0, h + 4, 4), d, n);
    unsigned char cb[4] = {c >> 24, c >> 16, c >> 8, c};
    fwrite(cb, 1, 4, f);
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: make_seeds OUTDIR SOURCE_DIR\n");
        return 2;
    }
    root = argv[1];
    const char *src = argv[2];
    mkdir(root, 0755);
    ss_error err;
    char *p, path[4096];

    /* ---- skin features.csv ---- */
    seed_text("skin_features", "each",
              "type,x,y,r,r2,h,m,p,w,x1,y1,x2,y2,x3,y3\n"
              "cysts,0.5,0.5,0.2,0,0.1,0,0,0,0,0,0,0,0,0\n"
              "moles,0.1,0.9,1,0,0.5,0.2,0,0,0,0,0,0,0,0\n"
              "freckles,0.99,0.01,0.8,0,0,0.1,0.01,0,0,0,0,0,0,0\n"
              "wrinkles,0.2,0.2,0,0,0.05,0,0,0.3,0.3,0.25,0.4,0.3,0.5,0.2\n"
              "follicles,0.7,0.3,0.04,0.1,0,0,0,0,0,0,0,0,0,0\n");
    seed_text("skin_features", "bad", "type,x,y,r,r2,h,m,p,w,x1,y1,x2,y2,x3,y3\nwarts,1,2\n");

    /* ---- stroke CSV ---- */
    seed_text("stroke_csv", "two",
              "u,v,stroke\n0.1,0.1,0\n0.4,0.1,0\n0.3,0.4,0\n0.6,0.6,1\n"
              "0.9,0.6,1\n0.75,0.9,1\n");
    seed_text("stroke_csv", "crlf", "0.2,0.2\r\n0.5,0.2\r\n0.4,0.6\r\n");
    seed_text("stroke_csv", "id_max",
              "0.2,0.2,2147483647\n0.5,0.2,2147483647\n0.4,0.6,2147483647\n");
    seed_text("stroke_csv", "tiny", "1e-320,0.5\n0.5,1e-320\n0.9,0.9\n");
    seed_text("stroke_csv", "nan", "nan,0.5\ninf,0.2\n0.4,-0\n");
    seed_text("stroke_csv", "collinear", "0.1,0.1\n0.2,0.2\n0.3,0.3\n0.4,0.4\n");
    char *longline = malloc(20001);
    memset(longline, '9', 20000);
    longline[0] = '0';
    longline[1] = '.';
    longline[20000] = '\0';
    seed_text("stroke_csv", "long_line", longline);
    free(longline);

    /* ---- timeline JSON ---- */
    seed_text(
        "timeline_json", "default",
        "{\"keys\":[{\"phase\":\"vasoconstriction\",\"day\":0},{\"phase\":\"vasodilation\","
        "\"day\":0.003},{\"phase\":\"scab_forming\",\"day\":0.02},{\"phase\":\"scab\",\"day\":"
        "0.75},{\"phase\":\"maturation\",\"day\":12}],\"end_day\":30}");
    seed_text("timeline_json", "unsorted",
              "{\"keys\":[{\"phase\":\"scab\",\"day\":5},{\"phase\":\"scab\",\"day\":1}],"
              "\"end_day\":1e308}");
    seed_text("timeline_json", "deep",
              "[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[{\"keys\":1}]]]]]]]]]]]]]]]");
    seed_text("timeline_json", "tiny",
              "{\"keys\":[{\"phase\":\"maturation\",\"day\":1e-320}],"
              "\"end_day\":1e-319}");

    /* ---- PNG ---- */
    ss_image *img = ss_image_create(7, 5, 3, &err);
    for (size_t i = 0; i < 7 * 5 * 3; i++) img->data[i] = (float)(i % 11) / 10.0f;
    static const struct { int ch, bits; } pv[] = {{1, 8}, {2, 16}, {3, 8}, {4, 16}};
    for (size_t k = 0; k < sizeof pv / sizeof *pv; k++) {
        ss_image *c = ss_image_create(7, 5, pv[k].ch, &err);
        for (size_t i = 0; i < 7 * 5 * (size_t)pv[k].ch; i++) c->data[i] = (float)(i % 5) / 4.0f;
        snprintf(path, sizeof path, "c%d_b%d", pv[k].ch, pv[k].bits);
        p = target_path("png", path);
        ss_png_write(p, c, pv[k].bits, SS_ENC_SRGB, &err);
        free(p);
        ss_image_free(c);
    }
    p = target_path("png", "bomb_30000");
    FILE *f = fopen(p, "wb");
    fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
    unsigned char ihdr[13] = {0, 0, 0x75, 0x30, 0, 0, 0x75, 0x30, 8, 2, 0, 0, 0};
    png_chunk(f, "IHDR", ihdr, 13);
    unsigned char raw[4] = {0}, z[64];
    uLongf zn = sizeof z;
    compress(z, &zn, raw, sizeof raw);
    png_chunk(f, "IDAT", z, (unsigned)zn);
    png_chunk(f, "IEND", NULL, 0);
    fclose(f);
    free(p);
    /* issue 21: 44 bytes whose tEXt claims 2^31-1; a 64 x 64 bilevel circle */
    p = target_path("png", "text_bomb");
    f = fopen(p, "wb");
    fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
    unsigned char ihdr1[13] = {0, 0, 0, 1, 0, 0, 0, 1, 8, 0, 0, 0, 0};
    png_chunk(f, "IHDR", ihdr1, 13);
    fwrite("\x7f\xff\xff\xfftEXtabc", 1, 11, f);
    fclose(f);
    free(p);
    p = target_path("png", "bilevel_64");
    f = fopen(p, "wb");
    fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
    unsigned char ihdr2[13] = {0, 0, 0, 64, 0, 0, 0, 64, 1, 0, 0, 0, 0};
    png_chunk(f, "IHDR", ihdr2, 13);
    unsigned char bits[64 * 9] = {0}, zb[1024];
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++)
            if ((x - 32) * (x - 32) + (y - 32) * (y - 32) < 400)
                bits[y * 9 + 1 + x / 8] |= (unsigned char)(0x80 >> (x % 8));
    zn = sizeof zb;
    compress(zb, &zn, bits, sizeof bits);
    png_chunk(f, "IDAT", zb, (unsigned)zn);
    png_chunk(f, "IEND", NULL, 0);
    fclose(f);
    free(p);

    /* ---- EXR ---- */
    p = target_path("exr", "rgb_half");
    ss_exr_write(p, img, 1, &err);
    free(p);
    p = target_path("exr", "rgb_float");
    ss_exr_write(p, img, 0, &err);
    free(p);

    /* ---- .mci ---- */
    static const char *mci_body = "2000\n0.01 0.01\n10 10 10\n1\n1.0\n1.0 10 90 0.75 0.02\n1.0\n";
    static const char *names[] = {"out.mco",  "../up.mco",     "/dev/null", "/etc/x.mco",
                                  "fuzz.mci", "a/../../b.mco", "."};
    for (size_t k = 0; k < sizeof names / sizeof *names; k++) {
        char *t = NULL;
        if (asprintf(&t, "1.0 # version\n1\n%s A\n%s", names[k], mci_body) < 0) return 1;
        snprintf(path, sizeof path, "name%zu", k);
        seed_text("mci", path, t);
        free(t);
    }
    seed_text("mci", "two_runs",
              "1.0\n2\na.mco A\n100\n0.01 0.01\n10 10 10\n2\n1.0\n1.37 1 100 0.9 0.1\n"
              "1.37 1 10 0 0.1\n1.0\nb.mco A\n100\n0.002 0.01\n10 50 10\n1\n1.0\n1.0 10 90 0.75 "
              "0.02\n1.0\n");
    seed_text("mci", "huge_grid",
              "1.0\n1\no.mco A\n1e15\n1e-300 1e-300\n2000000000 2000000000 "
              "2000000000\n1\n1.0\n1.0 10 90 0.75 0.02\n1.0\n");

    /* ---- ModelMatch table ---- */
    int ns[SS_MM_NAXES];
    double lo[SS_MM_NAXES], hi[SS_MM_NAXES];
    for (int a = 0; a < SS_MM_NAXES; a++) {
        ns[a] = a < 2 ? 2 : 1;
        ss_mm_axis_default_range(a, &lo[a], &hi[a]);
    }
    ss_mm_table *t = ss_mm_table_create(ns, lo, hi, &err);
    if (t) {
        for (size_t i = 0; i < t->nentries * SS_MM_NFIELDS; i++)
            t->entries[i] = 0.1 * (double)(i % 7);
        p = target_path("sstab", "small");
        ss_mm_table_write(p, t, &err);
        size_t len;
        char *b = slurp(p, &len);
        free(p);
        /* a header claiming 2^31 samples on an axis, resealed */
        if (len > 100) {
            char *c = malloc(len);
            memcpy(c, b, len);
            memset(c + 12, 0x7f, 4);
            reseal(c, len);
            seed("sstab", "huge_header", c, len);
            seed("sstab", "truncated", b, len / 2);
            free(c);
        }
        free(b);
        ss_mm_table_free(t);
    }

    /* ---- heal checkpoint ---- */
    ss_heal_grid *g = ss_heal_grid_create(4, 3, 5, 0.5, &err);
    ss_heal_params *hp = ss_heal_params_preset("clean", &err);
    char *pj = hp ? ss_heal_params_to_json(hp) : NULL;
    if (g && pj) {
        p = target_path("checkpoint", "small");
        ss_heal_checkpoint_write(p, g, "clean", pj, 1, 0.01, "{\"days\":1}", &err);
        size_t len;
        char *b = slurp(p, &len);
        free(p);
        char *c = malloc(len);
        memcpy(c, b, len);
        memset(c + 12, 0x7f, 4); /* nx = 2^31 - 1, resealed */
        reseal(c, len);
        seed("checkpoint", "huge_nx", c, len);
        seed("checkpoint", "truncated", b, len - 9);
        free(c);
        free(b);
    }
    /* ---- a heal snapshot (.vti): whole, with closure days, cut short,
     * without appended data, and with an absurd extent ---- */
    if (g) {
        p = target_path("vti", "small");
        double closed[4 * 3];
        for (int k = 0; k < 12; k++) closed[k] = k % 3 ? 1.5 * k : -1.0;
        ss_heal_vti_write_all(p, g, 0, NULL, NULL, closed, &err);
        size_t len;
        char *b = slurp(p, &len);
        free(p);
        seed("vti", "truncated", b, len / 2);
        char *app = strstr(b, "<AppendedData");
        if (app) seed("vti", "no_appended", b, (size_t)(app - b));
        char *we = strstr(b, "WholeExtent=\"0 4");
        if (we) { /* WholeExtent and Piece Extent 0 2147483647 in x */
            size_t head = (size_t)(we - b) + 15;
            char *c = malloc(len + 32);
            memcpy(c, b, head);
            int k = sprintf(c + head, "2147483647");
            memcpy(c + head + k, we + 16, len - head - 1);
            seed("vti", "huge_extent", c, len - 1 + (size_t)k);
            free(c);
        }
        free(b);
    }
    /* ---- the header of a checkpoint in pieces; a .pvti ---- */
    if (g && pj) {
        char *dir = target_path("ckpt_pieces", "run");
        const int dims[3] = {2, 1, 2};
        if (ss_heal_checkpoint_save_pieces(dir, g, "clean", pj, 1, 0.01, "{}", dims, 2, &err) ==
            SS_OK) {
            char hp[4400];
            ss_heal_ckpt_header_path(hp, sizeof hp, dir, g->step);
            seed_copy("ckpt_pieces", "two_by_two", hp, -1);
            size_t len;
            char *b = slurp(hp, &len);
            seed("ckpt_pieces", "truncated", b, len - 7);
            memset(b + 12, 0x7f, 4); /* nx = 2^31 - 1, resealed */
            reseal(b, len);
            seed("ckpt_pieces", "huge_nx", b, len);
            free(b);
        }
        ss_remove_tree(dir); /* the pieces themselves are no seeds */
        free(dir);
    }
    seed_text(
        "pvti", "three",
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PImageData\" version=\"1.0\" "
        "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <PImageData "
        "WholeExtent=\"0 6 0 4 0 3\" GhostLevel=\"0\" Origin=\"0 0 0\" Spacing=\"0.5 0.5 "
        "0.5\">\n    <PCellData Scalars=\"cell_state\">\n      <PDataArray type=\"UInt8\" "
        "Name=\"cell_state\"/>\n    </PCellData>\n    <Piece Extent=\"0 3 0 4 0 3\" "
        "Source=\"a&amp;b.vti\"/>\n    <Piece Extent=\"3 6 0 2 0 3\" Source=\"b.vti\"/>\n "
        "   <Piece Extent=\"3 6 2 4 0 3\" Source=\"/tmp/c.vti\"/>\n  </PImageData>\n</VTKFile>\n");
    seed_text("pvti", "overlap",
              "<VTKFile type=\"PImageData\"><PImageData WholeExtent=\"0 2147483647 0 4 0 3\" "
              "Spacing=\"1 1 1\"><Piece Extent=\"0 3 0 4 0 3\" Source=\"a.vti\"/><Piece "
              "Extent=\"-2 3 0 4 0 3\" Source=\"\"/></PImageData></VTKFile>");
    ss_heal_grid_free(g);

    /* ---- parameter JSON ---- */
    if (pj) seed_text("params_json", "clean_full", pj);
    free(pj);
    ss_heal_params_free(hp);
    for (int k = 0; k < 3; k++) {
        static const char *sc[3] = {"clean", "scab", "keloid"};
        snprintf(path, sizeof path, "%s/data/heal/%s.json", src, sc[k]);
        seed_copy("params_json", sc[k], path, -1);
    }
    seed_text("params_json", "bad_values",
              "{\"scenario\":\"keloid\",\"params\":{\"D1\":{\"value\":-1,\"unit\":\"mm^2/day\"},"
              "\"D2\":{\"value\":1e999,\"unit\":\"x\"}},\"switches\":{\"scab\":2}}");

    /* ---- OBJ ---- */
    seed_text("obj", "cube",
              "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
              "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
              "f 1/1 4/4 3/3 2/2\nf 5/1 6/2 7/3 8/4\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
    seed_text("obj", "negative", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3/-1/-1 -2//-1 -1\n");
    seed_text("obj", "bad_index", "v 0 0 0\nv 1 0 0\nf 1 2 2147483647\nf 0 1 2\n");

    /* ---- glTF (first byte: even = .glb, odd = .gltf) ---- */
    snprintf(path, sizeof path, "%s/data/meshes/generic-hand-left.glb", src);
    seed_copy("gltf", "hand_glb", path, 0);
    p = target_path("gltf", "square.gltf.tmp");
    snprintf(path, sizeof path, "%s", p);
    if (ss_gltf_write_textured_square(path, 0.1, "sq", "c.png", "m.png", "n.png", &err) == SS_OK)
        seed_copy("gltf", "square_gltf", path, 1);
    remove(path);
    free(p);
    seed_text(
        "gltf", "tri_uri",
        "\x01{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":36,\"uri\":\"data:"
        "application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],\"accessors\":[{\"bufferView\":0,"
        "\"componentType\":5126,\"count\":3,\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,0]}"
        "],\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0}}]}],\"nodes\":[{"
        "\"mesh\":0}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}");
    ss_image_free(img);
    return 0;
}
