/* Bounded, contained inputs (issue 21): PNGs of every bit depth read with
 * the right values; PNG chunks bounded by the file before libpng allocates;
 * whole-file reads refused by size before a byte is read; files named
 * inside a file (glTF buffers, .pvti pieces) held inside its folder; a
 * batch of springs equal to the same springs added one by one; a failed
 * EXR write that says why (the errno of the write; a real full disk where
 * a tmpfs can be mounted). The PNGs are written
 * here byte by byte (stored deflate blocks, CRC-32 and Adler-32 by hand),
 * so the reader is checked against an independent writer. */
#define _GNU_SOURCE
#include "testutil.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "skinsim/heal.h"
#include "skinsim/heal_io.h"
#include "skinsim/mech.h"

/* ---- a minimal PNG writer ------------------------------------------------- */

static uint32_t crc32_of(const unsigned char *p, size_t n, uint32_t c) {
    c = ~c;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

typedef struct buf {
    unsigned char *p;
    size_t n, cap;
} buf;

static void put(buf *b, const void *d, size_t n) {
    if (b->n + n > b->cap) {
        b->cap = (b->n + n) * 2 + 64;
        b->p = realloc(b->p, b->cap);
        assert_non_null(b->p);
    }
    memcpy(b->p + b->n, d, n);
    b->n += n;
}

static void put32(buf *b, uint32_t v) {
    unsigned char h[4] = {v >> 24, v >> 16, v >> 8, v};
    put(b, h, 4);
}

static void chunk(buf *b, const char *type, const unsigned char *d, size_t n) {
    put32(b, (uint32_t)n);
    size_t at = b->n;
    put(b, type, 4);
    if (n) put(b, d, n);
    put32(b, crc32_of(b->p + at, n + 4, 0));
}

/* w x h, depth bits, colour type 0 (grey) or 3 (palette of npal RGB
 * entries); sample(x, y) gives each value; one tEXt of text_len bytes. */
static buf make_png(int w, int h, int depth, int ctype, const unsigned char *pal, int npal,
                    int (*sample)(int, int), size_t text_len) {
    buf b = {0}, raw = {0}, z = {0};
    put(&b, "\x89PNG\r\n\x1a\n", 8);
    unsigned char ihdr[13] = {w >> 24,
                              w >> 16,
                              w >> 8,
                              w,
                              h >> 24,
                              h >> 16,
                              h >> 8,
                              h,
                              (unsigned char)depth,
                              (unsigned char)ctype,
                              0,
                              0,
                              0};
    chunk(&b, "IHDR", ihdr, 13);
    if (ctype == 3) chunk(&b, "PLTE", pal, 3 * (size_t)npal);
    if (text_len) {
        unsigned char *t = calloc(text_len, 1);
        memcpy(t, "Comment", 7); /* keyword, NUL, then zero text bytes */
        chunk(&b, "tEXt", t, text_len);
        free(t);
    }
    for (int y = 0; y < h; y++) {
        unsigned char zero = 0;
        put(&raw, &zero, 1); /* filter: none */
        unsigned acc = 0;
        int nb = 0;
        for (int x = 0; x < w; x++) {
            acc = (acc << depth) | (unsigned)sample(x, y);
            nb += depth;
            if (nb == 8) {
                unsigned char c = (unsigned char)acc;
                put(&raw, &c, 1);
                acc = 0, nb = 0;
            }
        }
        if (nb) {
            unsigned char c = (unsigned char)(acc << (8 - nb));
            put(&raw, &c, 1);
        }
    }
    /* zlib stream of stored blocks */
    put(&z, "\x78\x01", 2);
    uint32_t a = 1, s2 = 0;
    for (size_t i = 0; i < raw.n; i++) a = (a + raw.p[i]) % 65521, s2 = (s2 + a) % 65521;
    for (size_t off = 0; off < raw.n || off == 0;) {
        size_t n = raw.n - off > 65535 ? 65535 : raw.n - off;
        unsigned char hd[5] = {off + n == raw.n, n & 255, n >> 8, ~n & 255, (~n >> 8) & 255};
        put(&z, hd, 5);
        put(&z, raw.p + off, n);
        off += n;
        if (off == raw.n) break;
    }
    put32(&z, (s2 << 16) | a);
    chunk(&b, "IDAT", z.p, z.n);
    chunk(&b, "IEND", NULL, 0);
    free(raw.p);
    free(z.p);
    return b;
}

static int g_depth;
static int pattern(int x, int y) { return (x * 3 + y * 5 + x * y) % (1 << g_depth); }

static void test_png_low_depths(void **state) {
    (void)state;
    char *dir = tu_tmpdir("pngdepth");
    char path[600];
    ss_error err;
    unsigned char pal[16 * 3];
    for (int i = 0; i < 16; i++)
        pal[3 * i] = (unsigned char)(i * 17), pal[3 * i + 1] = (unsigned char)(255 - i * 5),
                pal[3 * i + 2] = (unsigned char)(i * 40 % 256);
    const int W = 13, H = 5; /* odd width: the last byte of a row is partial */
    for (int ct = 0; ct <= 3; ct += 3)
        for (int depth = 1; depth <= 8; depth *= 2) {
            if (ct == 3 && depth == 8)
                continue; /* 1, 2, 4-bit palettes; 8 is libpng's plain case */
            g_depth = depth;
            buf b = make_png(W, H, depth, ct, pal, 1 << depth, pattern, 0);
            snprintf(path, sizeof path, "%s/d%d_c%d.png", dir, depth, ct);
            assert_int_equal(ss_write_file_atomic(path, b.p, b.n, &err), SS_OK);
            free(b.p);
            ss_image *img = ss_png_read(path, SS_ENC_LINEAR, &err);
            if (!img) fail_msg("%s: %s", path, err.msg);
            assert_int_equal(img->width, W);
            assert_int_equal(img->height, H);
            assert_int_equal(img->channels, ct == 3 ? 3 : 1);
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    int v = pattern(x, y);
                    const float *px = ss_image_px(img, x, y);
                    if (ct == 0) {
                        float want = (float)(v * (255 / ((1 << depth) - 1))) / 255.0f;
                        assert_float_equal(px[0], want, 1e-6);
                    } else {
                        for (int c = 0; c < 3; c++)
                            assert_float_equal(px[c], pal[3 * v + c] / 255.0f, 1e-6);
                    }
                }
            ss_image_free(img);
        }
    tu_rmtree(dir);
    free(dir);
}

static int zero_px(int x, int y) { return (x + y) & 0; }

static void test_png_chunk_bounds(void **state) {
    (void)state;
    char *dir = tu_tmpdir("pngchunk");
    char path[600];
    ss_error err;
    /* the 44-byte PNG of the issue: a tEXt claiming 0x7fffffff bytes */
    buf b = {0};
    put(&b, "\x89PNG\r\n\x1a\n", 8);
    unsigned char ihdr[13] = {0, 0, 0, 1, 0, 0, 0, 1, 8, 0, 0, 0, 0};
    chunk(&b, "IHDR", ihdr, 13);
    put32(&b, 0x7fffffffu);
    put(&b, "tEXtabc", 7);
    assert_int_equal(b.n, 44);
    snprintf(path, sizeof path, "%s/bomb.png", dir);
    assert_int_equal(ss_write_file_atomic(path, b.p, b.n, &err), SS_OK);
    free(b.p);
    assert_null(ss_png_read(path, SS_ENC_LINEAR, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "bomb.png"));
    assert_non_null(strstr(err.msg, "chunk tEXt"));
    assert_non_null(strstr(err.msg, "2147483647"));
    /* an ancillary chunk the file does hold, but above the stated cap */
    g_depth = 8;
    b = make_png(4, 4, 8, 0, NULL, 0, zero_px, SS_PNG_MAX_ANCILLARY_BYTES + 1);
    snprintf(path, sizeof path, "%s/bigtext.png", dir);
    assert_int_equal(ss_write_file_atomic(path, b.p, b.n, &err), SS_OK);
    free(b.p);
    assert_null(ss_png_read(path, SS_ENC_LINEAR, &err));
    assert_non_null(strstr(err.msg, "ancillary chunk tEXt"));
    assert_non_null(strstr(err.msg, "8 MB"));
    /* a small one is fine */
    b = make_png(4, 4, 8, 0, NULL, 0, zero_px, 100);
    snprintf(path, sizeof path, "%s/text.png", dir);
    assert_int_equal(ss_write_file_atomic(path, b.p, b.n, &err), SS_OK);
    free(b.p);
    ss_image *img = ss_png_read(path, SS_ENC_LINEAR, &err);
    assert_non_null(img);
    ss_image_free(img);
    tu_rmtree(dir);
    free(dir);
}

/* ---- size limits of whole-file reads ---------------------------------------- */

static void test_read_limits(void **state) {
    (void)state;
    char *dir = tu_tmpdir("readmax");
    char path[600];
    ss_error err;
    snprintf(path, sizeof path, "%s/sparse.json", dir);
    int fd = open(path, O_CREAT | O_WRONLY | O_TRUNC, 0644);
    assert_true(fd >= 0);
    assert_int_equal(ftruncate(fd, (off_t)2 << 30), 0); /* 2 GB, no blocks */
    close(fd);
    size_t len = 0;
    assert_null(ss_read_file_max(path, &len, SS_READ_MAX_CONFIG, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "sparse.json"));
    assert_non_null(strstr(err.msg, "16 MB limit"));
    fd = open(path, O_WRONLY);
    assert_int_equal(ftruncate(fd, (off_t)5 << 30), 0); /* above SS_READ_MAX_ANY */
    close(fd);
    assert_null(ss_read_file(path, &len, &err));
    assert_non_null(strstr(err.msg, "4096 MB limit"));
    /* at the limit is fine */
    fd = open(path, O_WRONLY);
    assert_int_equal(ftruncate(fd, 1000), 0);
    close(fd);
    char *t = ss_read_file_max(path, &len, 1000, &err);
    assert_non_null(t);
    assert_int_equal(len, 1000);
    free(t);
    assert_null(ss_read_file_max(path, &len, 999, &err));
    tu_rmtree(dir);
    free(dir);
}

/* ---- references inside the referring file's folder ---------------------------- */

static void test_path_inside(void **state) {
    (void)state;
    char *dir = tu_tmpdir("inside");
    char p[600], q[600], ref[600];
    ss_error err;
    snprintf(p, sizeof p, "%s/scene", dir);
    assert_int_equal(ss_mkdir_p(p, &err), SS_OK);
    snprintf(p, sizeof p, "%s/secret.bin", dir);
    assert_int_equal(ss_write_file_atomic(p, "s", 1, &err), SS_OK);
    snprintf(p, sizeof p, "%s/scene/mesh.bin", dir);
    assert_int_equal(ss_write_file_atomic(p, "m", 1, &err), SS_OK);
    snprintf(p, sizeof p, "%s/scene/sub", dir);
    assert_int_equal(ss_mkdir_p(p, &err), SS_OK);
    snprintf(q, sizeof q, "%s/secret.bin", dir);
    snprintf(p, sizeof p, "%s/scene/link.bin", dir);
    assert_int_equal(symlink(q, p), 0);
    snprintf(p, sizeof p, "%s/scene/sub/in.bin", dir);
    assert_int_equal(ss_write_file_atomic(p, "i", 1, &err), SS_OK);
    snprintf(q, sizeof q, "%s/scene/a.gltf", dir);
    char *out = NULL;
    assert_int_equal(ss_input_path_inside(q, "mesh.bin", &out, &err), SS_OK);
    snprintf(p, sizeof p, "%s/scene/mesh.bin", dir);
    assert_string_equal(out, p);
    free(out);
    assert_int_equal(ss_input_path_inside(q, "sub/in.bin", &out, &err), SS_OK);
    free(out);
    const char *bad[] = {"../secret.bin", "sub/../../secret.bin", "link.bin", ".."};
    for (int k = 0; k < 4; k++) {
        out = (char *)1;
        assert_int_equal(ss_input_path_inside(q, bad[k], &out, &err), SS_ERR_INPUT);
        assert_null(out);
        assert_non_null(strstr(err.msg, bad[k]));
        assert_non_null(strstr(err.msg, "a.gltf"));
    }
    snprintf(ref, sizeof ref, "%s/secret.bin", dir); /* absolute */
    assert_int_equal(ss_input_path_inside(q, ref, &out, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "absolute"));
    tu_rmtree(dir);
    free(dir);
}

/* a .pvti whose piece lies outside its folder is refused naming the Source */
static void test_pvti_pieces_inside(void **state) {
    (void)state;
    char *dir = tu_tmpdir("pvtiout");
    char p[600], q[600];
    ss_error err;
    snprintf(p, sizeof p, "%s/run/fields", dir);
    assert_int_equal(ss_mkdir_p(p, &err), SS_OK);
    snprintf(p, sizeof p, "%s/other.vti", dir);
    assert_int_equal(ss_write_file_atomic(p, "x", 1, &err), SS_OK);
    snprintf(q, sizeof q, "%s/run/fields/link.vti", dir);
    assert_int_equal(symlink(p, q), 0);
    const char *src[3] = {"../../other.vti", "/etc/passwd", "link.vti"};
    const char *why[3] = {"'..'", "absolute", "resolves to"};
    for (int k = 0; k < 3; k++) {
        char text[1200];
        snprintf(text, sizeof text,
                 "<VTKFile type=\"PImageData\"><PImageData WholeExtent=\"0 4 0 4 0 4\" "
                 "Spacing=\"0.5 0.5 0.5\"><Piece Extent=\"0 4 0 4 0 4\" Source=\"%s\"/>"
                 "</PImageData></VTKFile>\n",
                 src[k]);
        snprintf(p, sizeof p, "%s/run/fields/f_%d.pvti", dir, k);
        assert_int_equal(ss_write_file_atomic(p, text, strlen(text), &err), SS_OK);
        assert_int_equal(ss_heal_pvti_check(p, &err), SS_ERR_INPUT);
        if (!strstr(err.msg, src[k]) || !strstr(err.msg, why[k]) || !strstr(err.msg, "f_"))
            fail_msg("case %d: %s", k, err.msg);
        float *disp = NULL;
        double *closed = NULL;
        assert_null(ss_heal_pvti_read(p, &disp, &closed, &err));
        assert_non_null(strstr(err.msg, src[k]));
    }
    tu_rmtree(dir);
    free(dir);
}

/* ---- springs in one batch == one by one ------------------------------------------ */

static void test_springs_batch(void **state) {
    (void)state;
    double x[3 * 5] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    int32_t tet[8] = {0, 1, 2, 3, 1, 2, 3, 4};
    ss_tetmesh m = {5, 2, x, tet};
    ss_error err;
    ss_springs *a = ss_springs_create(&m, 10.0, &err), *b = ss_springs_create(&m, 10.0, &err);
    assert_non_null(a);
    assert_non_null(b);
    int32_t ab[6] = {0, 4, 4, 2, 3, 0};
    double rest[3] = {0.5, 0.25, 0.125}, k[3] = {3.0, 5.0, 7.0};
    for (int i = 0; i < 3; i++)
        assert_int_equal(ss_springs_add(a, ab[2 * i], ab[2 * i + 1], rest[i], k[i], &err), SS_OK);
    assert_int_equal(ss_springs_add_many(b, 3, ab, rest, k, &err), SS_OK);
    assert_int_equal(a->nsprings, b->nsprings);
    assert_memory_equal(a->e, b->e, 2 * (size_t)a->nsprings * sizeof *a->e);
    assert_memory_equal(a->l0, b->l0, (size_t)a->nsprings * sizeof(double));
    assert_memory_equal(a->rest, b->rest, (size_t)a->nsprings * sizeof(double));
    assert_memory_equal(a->k, b->k, (size_t)a->nsprings * sizeof(double));
    const int32_t self[2] = {2, 2};
    assert_int_equal(ss_springs_add_many(b, 1, self, rest, k, &err), SS_ERR_INPUT);
    ss_springs_free(a);
    ss_springs_free(b);
}

/* ---- an EXR write that fails says why ------------------------------------------- */

static void test_exr_write_errno(void **state) {
    (void)state;
    char *dir = tu_tmpdir("exrfull");
    char path[600], msgpath[600];
    snprintf(path, sizeof path, "%s/x.exr", dir);
    snprintf(msgpath, sizeof msgpath, "%s/msg.txt", dir);
    /* a child whose files may not grow past 4 KB: its writes fail with
     * EFBIG as a full disk fails them with ENOSPC */
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        ss_error err;
        ss_image *img = ss_image_create(256, 256, 3, &err);
        for (size_t i = 0; img && i < 256 * 256 * 3; i++)
            img->data[i] = (float)((i * 2654435761u) % 1000) / 999.0f; /* incompressible-ish */
        FILE *f = fopen(msgpath, "w");
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit rl = {4096, 4096};
        setrlimit(RLIMIT_FSIZE, &rl);
        ss_status st = img ? ss_exr_write(path, img, 0, &err) : SS_ERR_NOMEM;
        fprintf(f, "%d %s\n", (int)st, st ? err.msg : "");
        fclose(f);
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    assert_true(WIFEXITED(status));
    ss_error err;
    char *msg = ss_read_file(msgpath, NULL, &err);
    assert_non_null(msg);
    assert_int_equal(atoi(msg), SS_ERR_RUNTIME);
    if (!strstr(msg, strerror(EFBIG))) fail_msg("no errno text in: %s", msg);
    assert_null(strstr(msg, "Error writing to stream"));
    free(msg);
    assert_false(tu_file_exists(path)); /* nothing half-written */
    /* a real full disk where we may mount one (root): a 200 KB tmpfs */
    char mnt[512];
    snprintf(mnt, sizeof mnt, "%s/disk", dir);
    mkdir(mnt, 0755);
    if (geteuid() == 0 && mount("tmpfs", mnt, "tmpfs", 0, "size=200k") == 0) {
        ss_image *img = ss_image_create(512, 512, 3, &err);
        assert_non_null(img);
        uint64_t r = 88172645463325252ull; /* noise: OpenEXR's zip cannot shrink it */
        for (size_t i = 0; i < 512 * 512 * 3; i++) {
            r ^= r << 13, r ^= r >> 7, r ^= r << 17;
            img->data[i] = (float)(r % 1000003) / 1000003.0f;
        }
        snprintf(path, sizeof path, "%s/x.exr", mnt);
        assert_int_equal(ss_exr_write(path, img, 0, &err), SS_ERR_RUNTIME);
        if (!strstr(err.msg, "No space left on device")) fail_msg("full disk: %s", err.msg);
        assert_int_equal(tu_count_entries(mnt), 0);
        ss_image_free(img);
        umount(mnt);
    }
    tu_rmtree(dir);
    free(dir);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_png_low_depths),     cmocka_unit_test(test_png_chunk_bounds),
        cmocka_unit_test(test_read_limits),        cmocka_unit_test(test_path_inside),
        cmocka_unit_test(test_pvti_pieces_inside), cmocka_unit_test(test_springs_batch),
        cmocka_unit_test(test_exr_write_errno),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
