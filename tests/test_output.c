/* The output discipline (src/core/output.c) and the input guards
 * (src/core/input.c) through their API: outputs appear whole or not at all,
 * an old output survives a failed run, a full disk and a swap that cannot
 * happen; hostile paths are refused before any work; one run per output;
 * leftovers of killed runs are cleaned; inputs never block and image
 * headers cannot claim more memory than there is. */
#define _GNU_SOURCE
#include "testutil.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

static char *path_in(const char *dir, const char *name) {
    char *p = NULL;
    if (asprintf(&p, "%s/%s", dir, name) < 0) return NULL;
    return p;
}

static void put(const char *path, const char *text) {
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static char *get(const char *path) {
    ss_error err;
    return ss_read_file(path, NULL, &err);
}

static void assert_text(const char *path, const char *want) {
    char *t = get(path);
    assert_non_null(t);
    assert_string_equal(t, want);
    free(t);
}

/* One file output of a fresh set: add, begin, write, finish. */
static ss_status run_file(const char *target, const char *text, ss_status work, ss_error *err) {
    ss_outputs *o = ss_outputs_create("test", err);
    ss_status st = ss_outputs_add(o, "--out", target, SS_OUTPUT_FILE, 100, err);
    if (!st) st = ss_outputs_begin(o, err);
    if (!st) st = ss_write_file_atomic(ss_outputs_path(o, 0), text, strlen(text), err);
    if (!st && work) st = ss_error_set(err, work, "the work failed");
    st = ss_outputs_finish(o, st, err);
    ss_outputs_free(o);
    return st;
}

static void test_file_whole_or_old(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-file");
    char *f = path_in(dir, "sub/x.csv");
    assert_int_equal(run_file(f, "one\n", SS_OK, &err), SS_OK);
    assert_text(f, "one\n");
    /* a failed run leaves the old one, and nothing else next to it */
    assert_int_equal(run_file(f, "two\n", SS_ERR_RUNTIME, &err), SS_ERR_RUNTIME);
    assert_text(f, "one\n");
    char *sub = path_in(dir, "sub");
    assert_int_equal(tu_count_entries(sub), 1);
    assert_int_equal(run_file(f, "three\n", SS_OK, &err), SS_OK);
    assert_text(f, "three\n");
    assert_int_equal(tu_count_entries(sub), 1);
    /* a failed run into a new place removes the folders it created */
    char *g = path_in(dir, "new/deeper/y.csv");
    assert_int_equal(run_file(g, "x", SS_ERR_RUNTIME, &err), SS_ERR_RUNTIME);
    char *nd = path_in(dir, "new");
    struct stat st;
    assert_int_not_equal(stat(nd, &st), 0);
    /* the failure message names the target, not the staging folder */
    assert_int_equal(run_file(f, "x", SS_OK, &err), SS_OK);
    ss_outputs *o = ss_outputs_create("test", &err);
    assert_int_equal(ss_outputs_add(o, NULL, f, SS_OUTPUT_FILE, 0, &err), SS_OK);
    assert_int_equal(ss_outputs_begin(o, &err), SS_OK);
    ss_error_set(&err, SS_ERR_RUNTIME, "%s: write failed", ss_outputs_path(o, 0));
    assert_int_equal(ss_outputs_finish(o, SS_ERR_RUNTIME, &err), SS_ERR_RUNTIME);
    assert_null(strstr(err.msg, "staging"));
    assert_non_null(strstr(err.msg, f));
    ss_outputs_free(o);
    free(nd);
    free(g);
    free(sub);
    free(f);
    tu_rmtree(dir);
    free(dir);
}

static void test_folder_replaced_whole(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-dir");
    char *d = path_in(dir, "run");
    for (int round = 0; round < 3; round++) {
        ss_outputs *o = ss_outputs_create("test", &err);
        assert_int_equal(ss_outputs_add(o, "--out", d, SS_OUTPUT_DIR, 0, &err), SS_OK);
        assert_int_equal(ss_outputs_begin(o, &err), SS_OK);
        char *a = path_in(ss_outputs_path(o, 0), round == 0 ? "a.txt" : "b.txt");
        assert_int_equal(ss_write_file_atomic(a, "x", 1, &err), SS_OK);
        /* round 2 fails: round 1's folder must be what stays */
        ss_status st = ss_outputs_finish(o, round == 2 ? SS_ERR_RUNTIME : SS_OK, &err);
        assert_int_equal(st, round == 2 ? SS_ERR_RUNTIME : SS_OK);
        ss_outputs_free(o);
        free(a);
        char *a0 = path_in(d, "a.txt"), *b0 = path_in(d, "b.txt");
        assert_int_equal(tu_file_exists(a0), round == 0); /* never a mix of runs */
        assert_int_equal(tu_file_exists(b0), round >= 1);
        assert_true(ss_output_dir_is_complete(d, "test"));
        assert_false(ss_output_dir_is_complete(d, "other"));
        assert_int_equal(tu_count_entries(dir), 1); /* no staging, lock or backup left */
        free(a0);
        free(b0);
    }
    /* a folder that is not this command's finished output is never replaced */
    ss_outputs *o = ss_outputs_create("other", &err);
    assert_int_equal(ss_outputs_add(o, "--out", d, SS_OUTPUT_DIR, 0, &err), SS_ERR_INPUT);
    /* ... and the message names the command whose output it is */
    assert_non_null(strstr(err.msg, "is a finished 'skinsim test' output folder, not a "
                                    "'skinsim other' one"));
    ss_outputs_free(o);
    char *m = path_in(d, SS_OUTPUT_MARKER);
    unlink(m);
    o = ss_outputs_create("test", &err);
    assert_int_equal(ss_outputs_add(o, "--out", d, SS_OUTPUT_DIR, 0, &err), SS_ERR_INPUT);
    ss_outputs_free(o);
    /* an empty folder is fine */
    char *e = path_in(dir, "empty");
    mkdir(e, 0755);
    o = ss_outputs_create("test", &err);
    assert_int_equal(ss_outputs_add(o, "--out", e, SS_OUTPUT_DIR, 0, &err), SS_OK);
    ss_outputs_free(o);
    free(e);
    free(m);
    free(d);
    tu_rmtree(dir);
    free(dir);
}

/* Each refused path: SS_ERR_INPUT at add, with the given words in the message. */
static void refused(ss_outputs *o, const char *path, ss_output_kind k, const char *words) {
    ss_error err;
    ss_error_clear(&err);
    assert_int_equal(ss_outputs_add(o, "--out", path, k, 0, &err), SS_ERR_INPUT);
    if (!strstr(err.msg, words)) fail_msg("'%s' lacks '%s'", err.msg, words);
}

static void test_hostile_paths_refused(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-hostile");
    ss_outputs *o = ss_outputs_create("test", &err);
    refused(o, "", SS_OUTPUT_FILE, "empty");
    refused(o, "", SS_OUTPUT_DIR, "empty");
    char *longp = malloc(5001);
    memset(longp, 'a', 5000);
    longp[0] = '/';
    longp[5000] = '\0';
    refused(o, longp, SS_OUTPUT_FILE, "too long");
    /* a 300-character name: the reason survives the cut message */
    char name[400];
    memset(name, 'n', 300);
    snprintf(name + 300, sizeof name - 300, ".png");
    char *lp = path_in(dir, name);
    refused(o, lp, SS_OUTPUT_FILE, "too long");
    refused(o, dir, SS_OUTPUT_FILE, "is a folder");
    char *slash = path_in(dir, "x/");
    refused(o, slash, SS_OUTPUT_FILE, "names a folder");
    char *fifo = path_in(dir, "pipe");
    assert_int_equal(mkfifo(fifo, 0644), 0);
    refused(o, fifo, SS_OUTPUT_FILE, "named pipe");
    refused(o, fifo, SS_OUTPUT_DIR, "named pipe");
    refused(o, "/dev/null", SS_OUTPUT_FILE, "character device");
    char *broken = path_in(dir, "broken");
    assert_int_equal(symlink("/nonexistent/target", broken), 0);
    refused(o, broken, SS_OUTPUT_FILE, "broken symbolic link");
    char *file = path_in(dir, "file");
    put(file, "keep");
    char *under = path_in(dir, "file/x.png");
    refused(o, under, SS_OUTPUT_FILE, "not a folder");
    refused(o, file, SS_OUTPUT_DIR, "not a folder");
    refused(o, "/", SS_OUTPUT_DIR, "root");
    /* two outputs naming one place (through ".." and a symlink too) */
    char *a = path_in(dir, "a.csv"), *a2 = path_in(dir, "sub/../a.csv");
    char *link = path_in(dir, "link.csv");
    put(a, "old");
    assert_int_equal(symlink(a, link), 0);
    assert_int_equal(ss_outputs_add(o, "--out", a, SS_OUTPUT_FILE, 0, &err), SS_OK);
    refused(o, a2, SS_OUTPUT_FILE, "same place");
    refused(o, link, SS_OUTPUT_FILE, "same place");
    char *d = path_in(dir, "d"), *din = path_in(dir, "d/inner.csv");
    assert_int_equal(ss_outputs_add(o, "--out", d, SS_OUTPUT_DIR, 0, &err), SS_OK);
    refused(o, din, SS_OUTPUT_FILE, "overlaps");
    /* an output that is an input, or a folder that holds one */
    assert_int_equal(ss_outputs_input(o, file, &err), SS_OK);
    refused(o, file, SS_OUTPUT_FILE, "input");
    ss_outputs_free(o);
    o = ss_outputs_create("test", &err);
    mkdir(d, 0755);
    assert_int_equal(ss_output_dir_mark_complete(d, "test", &err), SS_OK);
    put(din, "input");
    assert_int_equal(ss_outputs_input(o, din, &err), SS_OK);
    refused(o, d, SS_OUTPUT_DIR, "input");
    ss_outputs_free(o);
    /* nothing was created by any of it */
    assert_int_equal(tu_count_entries(dir), 6); /* pipe broken file a.csv link.csv d */
    assert_text(file, "keep");
    free(longp);
    free(lp);
    free(slash);
    free(fifo);
    free(broken);
    free(file);
    free(under);
    free(a);
    free(a2);
    free(link);
    free(d);
    free(din);
    tu_rmtree(dir);
    free(dir);
}

static void test_in_place_folder(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-inplace");
    char *d = path_in(dir, "run");
    /* a new folder is written where it stands, marked unfinished meanwhile */
    ss_outputs *o = ss_outputs_create("heal", &err);
    assert_int_equal(ss_outputs_add(o, "--out", d, SS_OUTPUT_DIR_IN_PLACE, 0, &err), SS_OK);
    assert_int_equal(ss_outputs_begin(o, &err), SS_OK);
    assert_string_equal(ss_outputs_path(o, 0), ss_outputs_target(o, 0));
    assert_true(ss_output_dir_is_unfinished(d, "heal"));
    assert_false(ss_output_dir_is_complete(d, NULL));
    /* while it runs, nobody else may start on it (and is told who holds it) */
    assert_int_equal(ss_output_lock_holder(d), (long)getpid());
    ss_outputs *b = ss_outputs_create("heal", &err);
    assert_int_equal(ss_outputs_add(b, "--out", d, SS_OUTPUT_DIR_IN_PLACE, 0, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "is writing it"));
    ss_outputs_free(b);
    char *f = path_in(d, "ckpt.bin");
    put(f, "progress");
    /* a failure leaves it, unfinished, for a resume */
    assert_int_equal(ss_outputs_finish(o, SS_ERR_RUNTIME, &err), SS_ERR_RUNTIME);
    ss_outputs_free(o);
    assert_text(f, "progress");
    assert_true(ss_output_dir_is_unfinished(d, "heal"));
    assert_int_equal(ss_output_lock_holder(d), 0);
    /* another owner may not take it; its owner resumes and completes it */
    o = ss_outputs_create("abrasion", &err);
    assert_int_equal(ss_outputs_add(o, "--out", d, SS_OUTPUT_DIR_IN_PLACE, 0, &err), SS_ERR_INPUT);
    ss_outputs_free(o);
    o = ss_outputs_create("heal", &err);
    assert_int_equal(ss_outputs_add(o, "--resume", d, SS_OUTPUT_DIR_IN_PLACE, 0, &err), SS_OK);
    assert_int_equal(ss_outputs_begin(o, &err), SS_OK);
    assert_int_equal(ss_outputs_finish(o, SS_OK, &err), SS_OK);
    ss_outputs_free(o);
    assert_true(ss_output_dir_is_complete(d, "heal"));
    assert_false(ss_output_dir_is_unfinished(d, NULL));
    assert_text(f, "progress");
    assert_int_equal(tu_count_entries(dir), 1);
    free(f);
    free(d);
    tu_rmtree(dir);
    free(dir);
}

/* The id of a process that has ended (a child, reaped). */
static long dead_pid(void) {
    pid_t p = fork();
    if (p == 0) _exit(0);
    assert_true(p > 0);
    waitpid(p, NULL, 0);
    return (long)p;
}

static void test_lock_and_stale_cleanup(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-lock");
    char *t = path_in(dir, "t.png");
    ss_outputs *a = ss_outputs_create("test", &err), *b = ss_outputs_create("test", &err);
    assert_int_equal(ss_outputs_add(a, "--out", t, SS_OUTPUT_FILE, 0, &err), SS_OK);
    assert_int_equal(ss_outputs_add(b, "--out", t, SS_OUTPUT_FILE, 0, &err), SS_OK);
    assert_int_equal(ss_outputs_begin(a, &err), SS_OK);
    /* a second run into the same output: refused, naming the holder */
    assert_int_equal(ss_outputs_begin(b, &err), SS_ERR_INPUT);
    char pid[32];
    snprintf(pid, sizeof pid, "process %ld", (long)getpid());
    if (!strstr(err.msg, pid)) fail_msg("'%s' does not name %s", err.msg, pid);
    ss_outputs_free(b);
    assert_int_equal(ss_write_file_atomic(ss_outputs_path(a, 0), "a", 1, &err), SS_OK);
    assert_int_equal(ss_outputs_finish(a, SS_OK, &err), SS_OK);
    ss_outputs_free(a);
    /* what killed runs leave, each named with the id of a process that is
     * gone: a staging folder (its marker inside), an atomic write's
     * temporary, a lock file, and a backup whose target is gone (a swap
     * killed half-way) */
    long dead = dead_pid();
    char name[128];
    snprintf(name, sizeof name, "t.png.skinsim-staging.%ld.AbCdEf", dead);
    char *st = path_in(dir, name);
    snprintf(name, sizeof name, "t.png.skinsim-tmp.%ld.Qw12Er", dead);
    char *tmp = path_in(dir, name);
    char *lock = path_in(dir, "t.png.skinsim-lock");
    mkdir(st, 0755);
    put(tmp, "half");
    snprintf(name, sizeof name, "skinsim-lock %ld\n", dead);
    put(lock, name);
    char *inner = path_in(st, "t.png"), *mark = path_in(st, SS_OUTPUT_STAGING);
    put(inner, "half-written");
    snprintf(name, sizeof name, "skinsim staging %ld\n", dead);
    put(mark, name);
    /* what only looks like it: the user's, never touched */
    static const char *const mine[] = {"t.png.partial-Xy12Zq", "t.png.tmp.Qw12Er",
                                       "t.png.skinsim-staging.mine", "t.png.skinsim-backup.x",
                                       "t.png.skinsim-tmp.1.2"};
    char *keep[7];
    for (int k = 0; k < 5; k++) {
        keep[k] = path_in(dir, mine[k]);
        put(keep[k], "mine");
    }
    /* a folder with a dead id but no skinsim marker, and one of a live process */
    snprintf(name, sizeof name, "t.png.skinsim-staging.%ld.UsEr01", dead);
    keep[5] = path_in(dir, name);
    mkdir(keep[5], 0755);
    char *kf = path_in(keep[5], "notes.txt");
    put(kf, "mine");
    snprintf(name, sizeof name, "t.png.skinsim-staging.%ld.LiVe01", (long)getppid());
    keep[6] = path_in(dir, name);
    mkdir(keep[6], 0755);
    assert_int_equal(run_file(t, "b", SS_OK, &err), SS_OK);
    assert_text(t, "b");
    assert_int_equal(tu_count_entries(dir), 1 + 7);
    for (int k = 0; k < 5; k++) assert_text(keep[k], "mine");
    assert_text(kf, "mine");
    snprintf(name, sizeof name, "t.png.skinsim-backup.%ld.ZZZZZZ", dead);
    char *bk = path_in(dir, name);
    assert_int_equal(rename(t, bk), 0);
    assert_int_equal(run_file(t, "c", SS_ERR_RUNTIME, &err), SS_ERR_RUNTIME);
    assert_text(t, "b"); /* the backup came back, then the failed run left it */
    assert_int_equal(tu_count_entries(dir), 1 + 7);
    /* a lock file of the user's: refused, kept as it is */
    char *t2 = path_in(dir, "u.png"), *lock2 = path_in(dir, "u.png.skinsim-lock");
    put(lock2, "mine\n");
    assert_int_equal(run_file(t2, "x", SS_OK, &err), SS_ERR_INPUT);
    if (!strstr(err.msg, "not a skinsim lock file")) fail_msg("'%s'", err.msg);
    assert_text(lock2, "mine\n");
    struct stat sb;
    assert_int_not_equal(lstat(t2, &sb), 0);
    free(t2);
    free(lock2);
    for (int k = 0; k < 7; k++) free(keep[k]);
    free(kf);
    free(st);
    free(tmp);
    free(lock);
    free(inner);
    free(mark);
    free(bk);
    free(t);
    tu_rmtree(dir);
    free(dir);
}

static void test_multi_output_rollback(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-multi");
    char *a = path_in(dir, "a.csv"), *b = path_in(dir, "b.csv");
    put(a, "old a");
    ss_outputs *o = ss_outputs_create("test", &err);
    assert_int_equal(ss_outputs_add(o, "--out", a, SS_OUTPUT_FILE, 0, &err), SS_OK);
    assert_int_equal(ss_outputs_add(o, "--radial-out", b, SS_OUTPUT_FILE, 0, &err), SS_OK);
    assert_int_equal(ss_outputs_begin(o, &err), SS_OK);
    assert_int_equal(ss_write_file_atomic(ss_outputs_path(o, 0), "new a", 5, &err), SS_OK);
    assert_int_equal(ss_write_file_atomic(ss_outputs_path(o, 1), "new b", 5, &err), SS_OK);
    /* during the run someone puts a pipe where b goes: it is not replaced,
     * and a is not left new while b failed */
    assert_int_equal(mkfifo(b, 0644), 0);
    assert_int_equal(ss_outputs_finish(o, SS_OK, &err), SS_ERR_RUNTIME);
    assert_non_null(strstr(err.msg, "named pipe"));
    ss_outputs_free(o);
    assert_text(a, "old a");
    struct stat st;
    assert_int_equal(lstat(b, &st), 0);
    assert_true(S_ISFIFO(st.st_mode));
    assert_int_equal(tu_count_entries(dir), 2);
    free(a);
    free(b);
    tu_rmtree(dir);
    free(dir);
}

/* A 1 MB tmpfs stands for a full disk (root only; skipped otherwise). */
static void test_full_disk(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-full");
    if (geteuid() != 0 || mount("tmpfs", dir, "tmpfs", 0, "size=1m") != 0) {
        tu_rmtree(dir);
        free(dir);
        skip();
    }
    char *f = path_in(dir, "out.bin");
    assert_int_equal(run_file(f, "old", SS_OK, &err), SS_OK);
    /* the estimate says it cannot fit: refused before any work */
    ss_outputs *o = ss_outputs_create("test", &err);
    assert_int_equal(ss_outputs_add(o, "--out", f, SS_OUTPUT_FILE, 5e6, &err), SS_OK);
    assert_int_equal(ss_outputs_begin(o, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "MB are free"));
    ss_outputs_free(o);
    /* the estimate was wrong: the disk fills during the write */
    o = ss_outputs_create("test", &err);
    assert_int_equal(ss_outputs_add(o, "--out", f, SS_OUTPUT_FILE, 1000, &err), SS_OK);
    assert_int_equal(ss_outputs_begin(o, &err), SS_OK);
    size_t n = 2 << 20;
    char *big = calloc(n, 1);
    ss_status st = ss_write_file_atomic(ss_outputs_path(o, 0), big, n, &err);
    assert_int_not_equal(st, SS_OK);
    assert_int_equal(ss_outputs_finish(o, st, &err), st);
    ss_outputs_free(o);
    assert_text(f, "old");
    assert_int_equal(tu_count_entries(dir), 1);
    free(big);
    free(f);
    umount(dir);
    tu_rmtree(dir);
    free(dir);
}

static void test_paths_under_a_folder(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("out-under");
    char *p = NULL;
    assert_int_equal(ss_path_under(dir, "x.mco", 0, &p, &err), SS_OK);
    char *want = path_in(dir, "x.mco");
    assert_string_equal(p, want);
    free(p);
    assert_int_equal(ss_path_under(dir, "sub/../y.mco", 0, &p, &err), SS_OK);
    free(p);
    assert_int_equal(ss_path_under(dir, "../x.mco", 0, &p, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "--allow-outside-paths"));
    assert_int_equal(ss_path_under(dir, "/etc/x.mco", 0, &p, &err), SS_ERR_INPUT);
    assert_int_equal(ss_path_under(dir, ".", 0, &p, &err), SS_ERR_INPUT);
    char *link = path_in(dir, "out");
    assert_int_equal(symlink("/tmp", link), 0);
    assert_int_equal(ss_path_under(dir, "out/x.mco", 0, &p, &err), SS_ERR_INPUT);
    assert_int_equal(ss_path_under(dir, "../x.mco", 1, &p, &err), SS_OK);
    free(p);
    free(link);
    free(want);
    tu_rmtree(dir);
    free(dir);
}

static void test_inputs_never_block(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("in-block");
    char *fifo = path_in(dir, "pipe.csv");
    assert_int_equal(mkfifo(fifo, 0644), 0);
    size_t n;
    assert_null(ss_read_file(fifo, &n, &err)); /* would block forever before */
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "named pipe"));
    assert_null(ss_png_read(fifo, SS_ENC_LINEAR, &err));
    assert_non_null(strstr(err.msg, "named pipe"));
    assert_null(ss_exr_read(fifo, &err));
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_null(ss_read_file("/dev/zero", &n, &err));
    assert_non_null(strstr(err.msg, "character device"));
    assert_null(ss_read_file(dir, &n, &err));
    assert_non_null(strstr(err.msg, "folder"));
    free(fifo);
    tu_rmtree(dir);
    free(dir);
}

static void chunk(FILE *f, const char *type, const unsigned char *data, unsigned len) {
    unsigned char hdr[8] = {len >> 24, len >> 16, len >> 8, len, 0, 0, 0, 0};
    memcpy(hdr + 4, type, 4);
    fwrite(hdr, 1, 8, f);
    if (len) fwrite(data, 1, len, f);
    uLong crc = crc32(0, hdr + 4, 4);
    if (len) crc = crc32(crc, data, len);
    unsigned char c[4] = {crc >> 24, crc >> 16, crc >> 8, crc};
    fwrite(c, 1, 4, f);
}

/* A PNG of a few dozen bytes whose header claims w x h RGB pixels. */
static void write_png_bomb(const char *path, unsigned w, unsigned h) {
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
    unsigned char ihdr[13] = {w >> 24, w >> 16, w >> 8, w, h >> 24, h >> 16, h >> 8, h, 8, 2};
    chunk(f, "IHDR", ihdr, 13);
    unsigned char raw[4] = {0}, z[64];
    uLongf zn = sizeof z;
    compress(z, &zn, raw, sizeof raw);
    chunk(f, "IDAT", z, (unsigned)zn);
    chunk(f, "IEND", NULL, 0);
    fclose(f);
}

static void test_png_header_bomb(void **state) {
    (void)state;
    ss_error err;
    char *dir = tu_tmpdir("in-bomb");
    char *p = path_in(dir, "bomb.png");
    write_png_bomb(p, 30000, 30000);
    struct stat st;
    stat(p, &st);
    assert_true(st.st_size < 100);
    double t0 = ss_now();
    assert_null(ss_png_read(p, SS_ENC_LINEAR, &err));
    assert_true(ss_now() - t0 < 5.0); /* guard against a hang, not a timing */
    assert_int_equal(err.code, SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "30000 x 30000"));
    /* a header that is fine for the file but not for the memory left */
    assert_int_equal(ss_image_check_alloc("x.png", 60000, 60000, 4, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "GB"));
    assert_int_equal(ss_image_check_alloc("x.png", 70000, 10, 1, &err), SS_ERR_INPUT);
    assert_int_equal(ss_image_check_alloc("x.png", 64, 64, 3, &err), SS_OK);
    /* under an address-space limit (ulimit -v), in a child process */
    pid_t pid = fork();
    if (pid == 0) {
        struct rlimit rl = {512ul << 20, 512ul << 20};
        setrlimit(RLIMIT_AS, &rl);
        ss_error e2;
        _exit(ss_image_check_alloc("x.png", 16000, 16000, 3, &e2) == SS_ERR_INPUT ? 0 : 1);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    free(p);
    tu_rmtree(dir);
    free(dir);
}

static void test_threads_and_messages(void **state) {
    (void)state;
    ss_error err;
    int n = 0;
    const char *bad[] = {"abc", "0", "-1", "2x", "4096", "", "99999999999999999999"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++)
        assert_int_equal(ss_threads_parse("SKINSIM_THREADS", bad[i], &n, &err), SS_ERR_INPUT);
    assert_non_null(strstr(err.msg, "SKINSIM_THREADS"));
    assert_int_equal(ss_threads_parse("SKINSIM_THREADS", "3", &n, &err), SS_OK);
    assert_int_equal(n, 3);
    /* a message with a 5000-character path keeps its reason (at the end) */
    char *longp = malloc(5001);
    memset(longp, 'p', 5000);
    longp[5000] = '\0';
    ss_error_set(&err, SS_ERR_INPUT, "%s: the reason is here", longp);
    assert_true(strlen(err.msg) < sizeof err.msg);
    assert_non_null(strstr(err.msg, "the reason is here"));
    free(longp);
    /* underflow is a number (as good as 0), overflow is not finite */
    double v;
    assert_int_equal(ss_text_parse_number("1e-320", &v), 0);
    assert_int_equal(ss_text_parse_number("1e999", &v), 2);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_file_whole_or_old),
        cmocka_unit_test(test_folder_replaced_whole),
        cmocka_unit_test(test_hostile_paths_refused),
        cmocka_unit_test(test_in_place_folder),
        cmocka_unit_test(test_lock_and_stale_cleanup),
        cmocka_unit_test(test_multi_output_rollback),
        cmocka_unit_test(test_full_disk),
        cmocka_unit_test(test_paths_under_a_folder),
        cmocka_unit_test(test_inputs_never_block),
        cmocka_unit_test(test_png_header_bomb),
        cmocka_unit_test(test_threads_and_messages),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
