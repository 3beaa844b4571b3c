/* skinsim core: errors, float images, PNG/EXR I/O, counter-based RNG, threads,
 * progress, atomic file writes and the output discipline (ss_outputs). Every
 * other module builds on these; none of it exits or aborts: failures come
 * back as an ss_status with a message that names the input and what was
 * wrong.
 *
 * What is stable, and what is not:
 *   - Stable API (kept across minor releases once MAJOR is 1; the soname
 *     libskinsim.so.MAJOR changes whenever one of these changes
 *     incompatibly; while MAJOR is 0, expect changes between minor
 *     releases): the error type and codes, ss_image and its PNG/EXR I/O,
 *     colour encoding, the counter-based RNG, threads, progress,
 *     ss_data_dir/ss_data_path/ss_version here, and the module headers
 *     optics.h, optics_fit.h, skin.h, texture.h, abrasion.h, wound.h,
 *     heal.h, heal_run.h, heal_io.h, mech.h, mesh.h, geom.h, paint.h,
 *     shell.h.
 *   - Exported for the skinsim programs, not stable (may change in any
 *     release): the file I/O helpers, the output discipline (ss_outputs_*,
 *     the staging and atomic-write helpers), the input checks (ss_input_*,
 *     ss_image_check_alloc, ss_memory_available_bytes) and the text helpers
 *     (ss_text_*). They are exported so the CLI and the examples share one
 *     implementation; a program outside skinsim should not depend on them.
 *   - Not API: names with a double underscore and the src/ headers
 *     (*_internal.h). dist.h (the MPI solvers) is not installed: those
 *     functions live only in the skinsim program (`mpirun skinsim ...`). */
#ifndef SKINSIM_CORE_H
#define SKINSIM_CORE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- errors ------------------------------------------------------------ */

/* Status codes. The CLI maps SS_ERR_INPUT to exit code 2 (usage and input
 * errors, including unwritable outputs) and anything else non-zero to 1. */
typedef enum ss_status {
    SS_OK = 0,
    SS_ERR_INPUT = 2,   /* bad argument, malformed or missing file, bad value */
    SS_ERR_RUNTIME = 1, /* failure while working (I/O error mid-run, ...) */
    SS_ERR_NOMEM = 3    /* allocation failed */
} ss_status;

typedef struct ss_error {
    ss_status code;
    char msg[1024];
} ss_error;

/* Records code and a printf-style message in err (which may be NULL) and
 * returns code, so callers can write `return ss_error_set(err, ...)`. */
ss_status ss_error_set(ss_error *err, ss_status code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
void ss_error_clear(ss_error *err);
/* Exit code the CLI uses for a status: 0, 1 or 2. */
int ss_status_exit_code(ss_status code);

/* ---- images -------------------------------------------------------------- */

/* float32, linear light, interleaved, row-major, origin top-left. */
typedef struct ss_image {
    int width, height, channels;
    float *data; /* width*height*channels floats */
} ss_image;

/* Returns NULL (and sets err) on a bad size or when memory runs out. Pixels are
 * zeroed. Sizes above SS_IMAGE_MAX_SIDE per side are refused. */
#define SS_IMAGE_MAX_SIDE 65536
/* Up to 16 channels: RGBA images, and parameter maps (skin and wound bio maps)
 * (file writers other than ss_exr_write_channels take 1-4). */
#define SS_IMAGE_MAX_CHANNELS 16
/* The PNG reader refuses an ancillary chunk (tEXt, iCCP, ...) longer than
 * this, and any chunk longer than what follows it in the file. */
#define SS_PNG_MAX_ANCILLARY_BYTES (8 << 20)
ss_image *ss_image_create(int width, int height, int channels, ss_error *err);
/* Same, pixels left undefined: for images the caller overwrites entirely. */
ss_image *ss_image_create_uninit(int width, int height, int channels, ss_error *err);
ss_image *ss_image_clone(const ss_image *img, ss_error *err);
void ss_image_free(ss_image *img);
static inline float *ss_image_px(const ss_image *img, int x, int y) {
    return img->data + ((size_t)y * (size_t)img->width + (size_t)x) * (size_t)img->channels;
}
void ss_image_fill(ss_image *img, const float *value);
/* Bilinear sample with wrap-around at (u,v) in 0..1; writes img->channels floats. */
void ss_image_sample_wrap(const ss_image *img, float u, float v, float *out);
/* Resample to a new size (bilinear, wrap-around); used for input textures of
 * another size than the output. */
ss_image *ss_image_resize(const ss_image *img, int width, int height, ss_error *err);
/* Maps one texel of the source (its channels) to `channels` floats (<= 4). */
typedef void (*ss_texel_map)(const float *texel, float *out, void *ctx);
/* ss_image_resize of the image map(img) (channels per texel), equal to it
 * float for float, reading only the texels the resampling needs. */
ss_image *ss_image_resize_mapped(const ss_image *img, int width, int height, int channels,
                                 ss_texel_map map, void *ctx, ss_error *err);

/* A contact sheet: tiles (any size, RGB or grey, linear) scaled into
 * tile_px squares on a dark canvas, `columns` per row, each labelled below
 * (labels may be NULL). Returns a linear RGB image. */
ss_image *ss_contact_sheet(const ss_image *const *tiles, const char *const *labels, int n,
                           int tile_px, int columns, ss_error *err);

/* ---- colour encoding ----------------------------------------------------- */
float ss_srgb_encode(float linear); /* linear 0..1 -> sRGB 0..1 */
float ss_srgb_decode(float encoded);
/* The same over arrays through a table with linear interpolation (error
 * below 2e-6), for whole images where powf per value would dominate. */
void ss_srgb_encode_array(const float *in, float *out, size_t n);

/* ---- file I/O ------------------------------------------------------------ */

typedef enum ss_encoding {
    SS_ENC_LINEAR = 0, /* data maps (height, roughness, masks, normals) */
    SS_ENC_SRGB = 1    /* colour: RGB channels sRGB-encoded, alpha linear */
} ss_encoding;

/* Writes 1-4 channel images as grey, grey+alpha, RGB or RGBA PNG with 8 or 16
 * bits per channel. Values are clamped to 0..1. Atomic: written to a
 * temporary name and renamed. */
ss_status ss_png_write(const char *path, const ss_image *img, int bits, ss_encoding enc,
                       ss_error *err);
/* Reads any PNG (palette, grey, 16 bit expanded); channels as stored after
 * expansion (1-4). SS_ENC_SRGB decodes colour channels to linear. */
ss_image *ss_png_read(const char *path, ss_encoding enc, ss_error *err);
/* Writes an OpenEXR scanline file (ZIP compressed) with half or float pixels;
 * channels named Y / YA / RGB / RGBA. Atomic. */
ss_status ss_exr_write(const char *path, const ss_image *img, int use_half, ss_error *err);
ss_image *ss_exr_read(const char *path, ss_error *err);
/* Any number of channels (1-64) with the given names, in the image's
 * channel order (a float map of several quantities, e.g. skin's bio.exr).
 * Reading: each named channel must exist; the image has them in that order. */
ss_status ss_exr_write_channels(const char *path, const ss_image *img, const char *const *names,
                                int use_half, ss_error *err);
ss_image *ss_exr_read_channels(const char *path, const char *const *names, int n, ss_error *err);
/* Picks PNG or EXR from the extension (.png, .exr). For PNG, enc applies. */
ss_image *ss_image_read(const char *path, ss_encoding enc, ss_error *err);

/* Atomic output file: write to path.skinsim-tmp.PID.XXXXXX, then rename on
 * commit (the name lets a later run prove a killed one's temporary is skinsim's). */
typedef struct ss_atomic_file {
    FILE *fp;
    char path[4096];
    char tmp[4200];
} ss_atomic_file;
ss_status ss_atomic_open(ss_atomic_file *af, const char *path, ss_error *err);
ss_status ss_atomic_commit(ss_atomic_file *af, ss_error *err); /* fflush+fsync+rename */
void ss_atomic_abort(ss_atomic_file *af);                      /* close and unlink */
/* Writes a whole buffer atomically. */
ss_status ss_write_file_atomic(const char *path, const void *data, size_t len, ss_error *err);
/* Reads a whole file (NUL-terminated for convenience); caller frees. The
 * size is checked (fstat) before anything is read or allocated: above
 * SS_READ_MAX_ANY or the memory available it is SS_ERR_INPUT naming the file
 * and the limit. ss_read_file_max takes a per-format limit (below). */
char *ss_read_file(const char *path, size_t *len, ss_error *err);
char *ss_read_file_max(const char *path, size_t *len, size_t max_bytes, ss_error *err);
/* Per-format size limits of whole-file reads (docs/reliability.md). */
#define SS_MB ((size_t)1 << 20)
#define SS_READ_MAX_ANY ((size_t)4096 * SS_MB)    /* anything else (checkpoints, snapshots) */
#define SS_READ_MAX_CONFIG ((size_t)16 * SS_MB)   /* params, timeline, recipe JSON, .mci, spectra */
#define SS_READ_MAX_STROKES ((size_t)64 * SS_MB)  /* stroke CSV */
#define SS_READ_MAX_FEATURES ((size_t)64 * SS_MB) /* skin features CSV */
#define SS_READ_MAX_TABLE ((size_t)512 * SS_MB)   /* the ModelMatch .sstab table */
#define SS_READ_MAX_MESH ((size_t)1024 * SS_MB)   /* OBJ, glTF JSON, GLB, glTF buffers */
/* mkdir -p; an existing directory is fine, a file in the way is an input error. */
ss_status ss_mkdir_p(const char *path, ss_error *err);
/* Checks that dir exists (or can be created) and a file can be created in it. */
ss_status ss_check_writable_dir(const char *dir, ss_error *err);
/* rm -rf of a directory tree (used to clean up a failed staging directory). */
void ss_remove_tree(const char *path);

/* ---- outputs: checked before work, staged, swapped in whole --------------
 *
 * Every command writes every output (a single file or a folder) through one
 * ss_outputs set (src/core/output.c, docs/reliability.md):
 *
 *     ss_outputs *outs = ss_outputs_create("abrasion", &err);
 *     st = ss_outputs_input(outs, stroke_csv, &err);        // may not be overwritten
 *     st = ss_outputs_add(outs, "--out", dir, SS_OUTPUT_DIR, bytes_estimate, &err);
 *     ...read and check the inputs...
 *     st = ss_outputs_begin(outs, &err);                    // lock, clean, disk, stage
 *     ...write everything under ss_outputs_path(outs, 0)...
 *     st = ss_outputs_finish(outs, st, &err);               // swap in, or roll back
 *     ss_outputs_free(outs);
 *
 * add checks a path at once, without touching the disk: empty, too long, a
 * broken symlink, a device, pipe or socket (never replaced), a folder where a
 * file is wanted, a folder that is not this command's finished output (no
 * completion marker), two outputs naming the same place, an output that is
 * or holds an input: each is SS_ERR_INPUT naming the option and the path.
 * begin creates missing parent folders, takes NAME.skinsim-lock (a second run
 * into the same output gets SS_ERR_INPUT naming the process that holds it; the
 * kernel drops the lock when a run dies), removes what killed runs left next
 * to the target, refuses (SS_ERR_INPUT) when the estimates exceed the free
 * space, and makes a staging folder NAME.skinsim-staging.PID.XXXXXX next to
 * each target. finish(SS_OK) marks folders complete (.skinsim-complete) and
 * swaps each staged output in with one rename (the old one stays until all
 * are in, and comes back if any swap fails); finish(error) removes the
 * staging and the folders begin created, leaving every old output as it was,
 * and rewrites staging paths in err back to the names the user gave. */
typedef enum ss_output_kind {
    SS_OUTPUT_FILE = 0, /* one regular file */
    SS_OUTPUT_DIR = 1,  /* a folder the command owns and replaces whole */
    /* A folder written where it stands, for runs that must survive a kill
     * and be resumed from what they wrote (heal's checkpoints). It may be
     * new, empty, or this owner's folder (finished or not); begin marks it
     * unfinished (.skinsim-unfinished), finish(SS_OK) marks it complete,
     * finish(error) leaves it unfinished for a resume. Nothing else of the
     * discipline changes (checks, lock, leftovers, disk space). */
    SS_OUTPUT_DIR_IN_PLACE = 2
} ss_output_kind;
typedef struct ss_outputs ss_outputs;

/* owner: the command name written into the completion marker of its
 * folders ("abrasion"); an existing folder is replaced only when its marker
 * names the same owner (or it is empty). NULL on out of memory. */
ss_outputs *ss_outputs_create(const char *owner, ss_error *err);
/* Registers an input file: no output may be it or contain it. Missing
 * inputs are ignored here (their reader reports them). */
ss_status ss_outputs_input(ss_outputs *o, const char *path, ss_error *err);
/* Adds output number ss_outputs_count() (0, 1, ...). label names it in
 * messages ("--out"); bytes is the estimated size written (0 = unknown). */
ss_status ss_outputs_add(ss_outputs *o, const char *label, const char *path, ss_output_kind kind,
                         double bytes, ss_error *err);
int ss_outputs_count(const ss_outputs *o);
ss_status ss_outputs_begin(ss_outputs *o, ss_error *err);
/* Where output i is written between begin and finish: the staging folder
 * itself for SS_OUTPUT_DIR, a file of the target's name inside it for
 * SS_OUTPUT_FILE (so extensions are kept). */
const char *ss_outputs_path(const ss_outputs *o, int i);
/* The resolved absolute target of output i (symlinks followed). */
const char *ss_outputs_target(const ss_outputs *o, int i);
ss_status ss_outputs_finish(ss_outputs *o, ss_status status, ss_error *err);
/* Rolls back anything begun and not finished, releases locks, frees. */
void ss_outputs_free(ss_outputs *o);
/* The process id of the skinsim run writing path now (holding its lock),
 * -1 when that run's id is unreadable, 0 when no run is writing it. */
long ss_output_lock_holder(const char *path);
/* 1 when dir holds a completion marker (of owner, or of any owner when NULL). */
int ss_output_dir_is_complete(const char *dir, const char *owner);
/* Writes or removes dir's completion marker (for outputs a command keeps
 * updating in place, such as a resumable run). */
ss_status ss_output_dir_mark_complete(const char *dir, const char *owner, ss_error *err);
ss_status ss_output_dir_mark_incomplete(const char *dir, ss_error *err);
/* 1 when dir is an unfinished in-place folder of owner (or any when NULL). */
int ss_output_dir_is_unfinished(const char *dir, const char *owner);
#define SS_OUTPUT_MARKER ".skinsim-complete"
#define SS_OUTPUT_UNFINISHED ".skinsim-unfinished"
/* Inside a staging folder while a run writes it ("skinsim staging PID"). */
#define SS_OUTPUT_STAGING ".skinsim-staging"
/* The temporary name of an atomic file: PATH.skinsim-tmp.PID.XXXXXX. */
#define SS_ATOMIC_TMP ".skinsim-tmp."

/* An output path named by an input file (an .mci's run outputs): name is
 * taken relative to base_dir; absolute names and names that leave base_dir
 * (after "..", symlinks followed) are SS_ERR_INPUT unless allow_outside.
 * *out is malloc'd. */
ss_status ss_path_under(const char *base_dir, const char *name, int allow_outside, char **out,
                        ss_error *err);
/* A file named inside another file (a glTF buffer or image URI, a .pvti
 * piece), already percent-decoded: resolved against the folder of referrer
 * and refused (SS_ERR_INPUT naming the reference and the referrer) when it
 * is absolute, has a ".." component, or resolves (symlinks followed) outside
 * that folder. *out (malloc'd) is the folder joined with ref. */
ss_status ss_input_path_inside(const char *referrer, const char *ref, char **out, ss_error *err);

/* ---- inputs: never block, never allocate what the machine lacks --------- */

/* Opens an input for reading after checking it is a regular file (a named
 * pipe without writer, a device, a socket or a folder is SS_ERR_INPUT, and
 * the open never blocks). *size (may be NULL) gets its size. */
int ss_input_open_fd(const char *path, size_t *size, ss_error *err);
FILE *ss_input_open(const char *path, size_t *size, ss_error *err);
/* Memory this process can still allocate, in bytes: the smallest of the
 * available memory, its address-space limit and its cgroup's limit. */
double ss_memory_available_bytes(void);
/* Checks a width x height x channels float image named by an input header
 * before it is allocated: sides within SS_IMAGE_MAX_SIDE and the bytes
 * within the available memory, else SS_ERR_INPUT naming the size. */
ss_status ss_image_check_alloc(const char *name, long width, long height, int channels,
                               ss_error *err);

/* Text helpers for file readers. next_line: copies the next line of p
 * (\n, \r\n or \r endings) into buf, truncating and setting *too_long when
 * it does not fit; returns the rest of the text, NULL at the end. trim: strips
 * blanks in place. parse_number: the whole token as a finite double; returns
 * 0, 1 (not a number) or 2 (not finite). */
const char *ss_text_next_line(const char *p, char *buf, size_t bufsize, int *too_long);
char *ss_text_trim(char *s);
int ss_text_parse_number(const char *s, double *out);

/* Directory with the shipped data files: $SKINSIM_DATA, else the
 * share/skinsim folder of an installed copy (found next to the library or
 * program file, else next to a libskinsim on the program's library search
 * path, e.g. the RUNPATH `pkg-config --static --libs skinsim` sets; so an
 * installed tree can be moved), else the source data directory for code
 * running from its build folder, else the configured install folder. */
const char *ss_data_dir(void);
/* The shipped ModelMatch table, relative to ss_data_dir() (the table that
 * `skinsim wound` and `skinsim skin` use when given none). */
#define SS_DATA_DEFAULT_TABLE "modelmatch_default.sstab"
/* Full path of the shipped data file `name` (relative to ss_data_dir(), e.g.
 * SS_DATA_DEFAULT_TABLE or "spectra/d65.csv") in out[outsize]. Returns
 * SS_ERR_INPUT naming the path when it cannot be read (or name is empty,
 * absolute or climbs out with ".."), or when it does not fit in out. */
ss_status ss_data_path(const char *name, char *out, size_t outsize, ss_error *err);
/* The library's version, "MAJOR.MINOR.PATCH" (the shared library's soname
 * carries MAJOR). */
const char *ss_version(void);

/* ---- random numbers ------------------------------------------------------ */

/* Counter-based generator (Philox4x32-10): every draw is a pure function of
 * (seed, stream, index), so results do not depend on thread count or order. */
void ss_rng4(uint64_t seed, uint64_t stream, uint64_t index, uint32_t out[4]);
uint32_t ss_rng_u32(uint64_t seed, uint64_t stream, uint64_t index);
/* Uniform in [0,1) with 53 random bits. */
double ss_rng_uniform(uint64_t seed, uint64_t stream, uint64_t index);

/* Bulk fills for textures: out[i] is the draw at index first + i, where
 * index k is lane k % 4 of Philox block k / 4, so a fill is 4x cheaper than
 * per-value calls and any sub-range gives the same values. f32 values are
 * uniform in [0,1) with 24 random bits. Parallel (OpenMP), deterministic. */
void ss_rng_fill_u32(uint64_t seed, uint64_t stream, uint64_t first, uint32_t *out, size_t n);
void ss_rng_fill_f32(uint64_t seed, uint64_t stream, uint64_t first, float *out, size_t n);

/* A sequential view of one (seed, stream): for loops that need many draws,
 * such as one photon's walk. Draw k of the stream is a function of k only. */
typedef struct ss_rng_seq {
    uint64_t seed, stream, counter;
    uint32_t buf[4];
    int left;
} ss_rng_seq;
void ss_rng_seq_init(ss_rng_seq *r, uint64_t seed, uint64_t stream);
uint32_t ss_rng_seq_u32(ss_rng_seq *r);
double ss_rng_seq_uniform(ss_rng_seq *r);      /* [0,1) */
double ss_rng_seq_uniform_open(ss_rng_seq *r); /* (0,1), safe for log() */

/* ---- threads ------------------------------------------------------------- */

/* Thread count: n > 0 uses n; n == 0 uses $SKINSIM_THREADS, else all cores.
 * Returns the count in force. */
int ss_threads_set(int n);
/* Largest thread count accepted (--threads and SKINSIM_THREADS). */
#define SS_THREADS_MAX 1024
/* Parses a thread count as --threads and $SKINSIM_THREADS take it: an
 * integer 1..SS_THREADS_MAX; what names the source in the message. */
ss_status ss_threads_parse(const char *what, const char *s, int *n, ss_error *err);
/* Checks $SKINSIM_THREADS (unset or empty is fine): SS_ERR_INPUT otherwise. */
ss_status ss_threads_check_env(ss_error *err);
int ss_threads_get(void);

/* ---- progress ------------------------------------------------------------ */

/* A progress bar on stderr, drawn only when stderr is a terminal and not quiet.
 * With SKINSIM_PROGRESS_FD=N (N >= 3) in the environment each redraw (at most
 * 10 a second, and at the end) also writes "skinsim-progress LABEL FRACTION\n"
 * to descriptor N, quiet or not: how a parent process (the Blender add-on)
 * follows a command. enabled: 0 off, 1 the bar, 2 the lines, 3 both. */
typedef struct ss_progress {
    const char *label;
    double total, done;
    int enabled;
    double last_draw, start;
} ss_progress;
void ss_progress_begin(ss_progress *p, const char *label, double total, int quiet);
void ss_progress_update(ss_progress *p, double done);
void ss_progress_end(ss_progress *p);

/* A long call's optional progress and cancel callback (the *_poll calls:
 * ss_skin_generate_poll, ss_skin_bio_maps_poll, ss_skin_render_maps_poll,
 * ss_abrasion_frame_poll, ss_wound_render_poll). fn(user, fraction) is
 * called from the calling thread only, outside any parallel region, between
 * bands of rows (or between a call's stages or feature types), with the fraction done (0..1,
 * rising). A non-zero return stops the call at that point: it frees what it allocated and returns
 * SS_ERR_RUNTIME with the message "...: cancelled"; images it would have allocated are not
 * returned, and images the caller passed in for the output are partly written (their contents are
 * unspecified). fn NULL: never polled. Results of calls that are not cancelled do not depend on fn.
 */
typedef int (*ss_progress_fn)(void *user, double fraction);

/* Physical memory of this machine in bytes (0 if unknown): what commands
 * check a job's estimated size against before they start, so a job that
 * cannot fit is an input error rather than an out-of-memory kill. */
double ss_memory_physical_bytes(void);

/* Wall clock in seconds (monotonic). */
double ss_now(void);

#ifdef __cplusplus
}
#endif
#endif
