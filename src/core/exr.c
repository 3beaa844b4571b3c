/* OpenEXR read/write through OpenEXR's C API (OpenEXRCore 3.1).
 *
 * Design: our float32 interleaved buffer is handed to the encode/decode
 * pipelines as one strided pointer per channel (user_data_type FLOAT, pixel
 * stride = channels*4, line stride = width*channels*4). Writing, the library
 * converts to HALF or FLOAT and applies ZIP compression. Channel order on
 * disk is alphabetical (A,B,G,R), so every channel is matched by name, never
 * by position.
 *
 * All file access goes through our own callbacks (pread/pwrite on a file
 * descriptor) so that the context's user_data is ours: the error handler
 * stores the library's first message there instead of printing it, and the
 * reader reports a missing file with the OS error. Writing goes to the
 * temporary file of ss_atomic_open and is renamed into place only when the
 * whole file (header, chunks, offset table) was written: on failure nothing
 * is left behind.
 *
 * Reading: part 0 of a scanline file; tiled and deep parts are refused with a
 * clear message. Output is the data window (which may be offset): R,G,B[,A]
 * when R, G and B exist, else Y[,A]; other channels are ignored. The library
 * reads and decompresses each chunk, but the last step (unpacking the
 * decompressed samples into our floats) is our own unpack_to_float():
 * OpenEXRCore 3.1.5's default routines have fast paths that swap channels
 * (4-channel half->float interleaved comes out as A,B,G,R) and that write
 * through NULL pointers when only some of 3-4 half channels are wanted. */
#define _POSIX_C_SOURCE 200809L
#include "skinsim/core.h"

#include <OpenEXR/openexr.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define SS_EXR_ZIP_LEVEL 1

/* Shared by the I/O callbacks and the quiet error handler (context user_data). */
typedef struct exr_io {
    int fd;
    char msg[256];   /* first message the library reported */
    int write_errno; /* errno of a failed write (ENOSPC on a full disk) */
} exr_io;

static void quiet_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
    void *ud = NULL;
    if (exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud) return;
    exr_io *io = ud;
    if (!io->msg[0])
        snprintf(io->msg, sizeof io->msg, "%s", msg ? msg : exr_get_default_error_message(code));
}

static int64_t io_read(exr_const_context_t ctxt, void *ud, void *buf, uint64_t sz, uint64_t off,
                       exr_stream_error_func_ptr_t error_cb) {
    (void)ctxt;
    (void)error_cb;
    exr_io *io = ud;
    uint64_t done = 0;
    while (done < sz) {
        ssize_t n = pread(io->fd, (char *)buf + done, (size_t)(sz - done), (off_t)(off + done));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) return -1;
        if (n == 0) break; /* end of file: short read, the library reports it */
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int64_t io_size(exr_const_context_t ctxt, void *ud) {
    (void)ctxt;
    struct stat st;
    return fstat(((exr_io *)ud)->fd, &st) == 0 ? (int64_t)st.st_size : -1;
}

static int64_t io_write(exr_const_context_t ctxt, void *ud, const void *buf, uint64_t sz,
                        uint64_t off, exr_stream_error_func_ptr_t error_cb) {
    (void)ctxt;
    (void)error_cb;
    exr_io *io = ud;
    uint64_t done = 0;
    while (done < sz) {
        ssize_t n =
            pwrite(io->fd, (const char *)buf + done, (size_t)(sz - done), (off_t)(off + done));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) { /* kept: the library only says "Error writing to stream" */
            io->write_errno = n < 0 ? errno : ENOSPC;
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static exr_context_initializer_t make_init(exr_io *io) {
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet_handler;
    init.user_data = io;
    return init;
}

/* The library's own message when it gave one, else the text for the code. */
static const char *why(const exr_io *io, exr_result_t rv) {
    return io->msg[0] ? io->msg : exr_get_default_error_message(rv);
}

/* Index of a channel in our interleaved layout for the given channel names, or -1. */
static int chan_index(const char *name, const char *const *names, int n) {
    for (int i = 0; i < n; i++)
        if (strcmp(name, names[i]) == 0) return i;
    return -1;
}

/* Points every pipeline channel we have at its place in the float buffer
 * (rows starting at `row`); channels we do not want get NULL (skipped). */
static void bind_channels(exr_coding_channel_info_t *ch, int count, const char *const *names,
                          int nch, float *data, int width, int row) {
    for (int c = 0; c < count; c++) {
        int k = chan_index(ch[c].channel_name, names, nch);
        ch[c].user_bytes_per_element = 4;
        ch[c].user_data_type = EXR_PIXEL_FLOAT;
        ch[c].user_pixel_stride = nch * 4;
        ch[c].user_line_stride = width * nch * 4;
        ch[c].decode_to_ptr =
            k < 0 ? NULL
                  : (uint8_t *)(data + ((size_t)row * (size_t)width * (size_t)nch + (size_t)k));
    }
}

static float half_to_float(uint16_t h) {
    int e = (h >> 10) & 31, m = h & 1023;
    float v = e == 0    ? ldexpf((float)m, -24)
              : e == 31 ? (m ? NAN : INFINITY)
                        : ldexpf((float)(m | 1024), e - 25);
    return (h & 0x8000) ? -v : v;
}

/* Unpack step of the decode pipeline. The decompressed chunk holds, line by
 * line, each channel's samples in file order (little-endian HALF, FLOAT or
 * UINT; subsampled channels only on their lines). Wanted channels are
 * converted to float at their strided place, the others skipped. */
static exr_result_t unpack_to_float(exr_decode_pipeline_t *d) {
    const uint8_t *src = d->unpacked_buffer;
    uint64_t avail = d->chunk.unpacked_size;
    if (!d->decompress_fn && d->chunk.packed_size < avail) avail = d->chunk.packed_size;
    const uint8_t *end = src + avail;
    for (int y = 0; y < d->chunk.height; y++)
        for (int c = 0; c < d->channel_count; c++) {
            const exr_coding_channel_info_t *ch = &d->channels[c];
            if (ch->height == 0 ||
                (ch->y_samples > 1 && (d->chunk.start_y + y) % ch->y_samples != 0))
                continue;
            int bpe = ch->bytes_per_element;
            if ((uint64_t)(end - src) < (uint64_t)ch->width * (uint64_t)bpe)
                return EXR_ERR_CORRUPT_CHUNK;
            if (ch->decode_to_ptr) {
                uint8_t *row = ch->decode_to_ptr + (size_t)y * (size_t)ch->user_line_stride;
                for (int x = 0; x < ch->width; x++) {
                    const uint8_t *b = src + (size_t)x * (size_t)bpe;
                    uint32_t u = bpe == 2 ? (uint32_t)(b[0] | b[1] << 8)
                                          : (uint32_t)b[0] | (uint32_t)b[1] << 8 |
                                                (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
                    float f;
                    if (ch->data_type == EXR_PIXEL_HALF)
                        f = half_to_float((uint16_t)u);
                    else if (ch->data_type == EXR_PIXEL_FLOAT)
                        memcpy(&f, &u, sizeof f);
                    else
                        f = (float)u;
                    memcpy(row + (size_t)x * (size_t)ch->user_pixel_stride, &f, sizeof f);
                }
            }
            src += (size_t)ch->width * (size_t)bpe;
        }
    return EXR_ERR_SUCCESS;
}

static const char *const NAMES[5][4] = {
    {0}, {"Y"}, {"Y", "A"}, {"R", "G", "B"}, {"R", "G", "B", "A"}};

ss_status ss_exr_write(const char *path, const ss_image *img, int use_half, ss_error *err) {
    if (!img || !img->data || img->width <= 0 || img->height <= 0 || img->channels < 1 ||
        img->channels > 4)
        return ss_error_set(err, SS_ERR_INPUT, "%s: EXR needs a 1-4 channel image of positive size",
                            path);
    return ss_exr_write_channels(path, img, NAMES[img->channels], use_half, err);
}

/* Chunks are packed and compressed by the threads in batches of
 * EXR_BATCH (each thread its own pipeline; OpenEXRCore allows that on one
 * context) and written in order by one thread, so the file is the same
 * bytes for any thread count. */
#define EXR_BATCH 32
typedef struct exr_slot {
    exr_encode_pipeline_t enc;
    exr_chunk_info_t ci;
    int have;
    exr_result_t rv;
} exr_slot;

static exr_result_t write_chunks(exr_context_t ctx, int part, const ss_image *img,
                                 const char *const *names, int spc) {
    exr_slot *slot = calloc(EXR_BATCH, sizeof *slot);
    if (!slot) return EXR_ERR_OUT_OF_MEMORY;
    exr_result_t rv = EXR_ERR_SUCCESS;
    int nchunks = (img->height + spc - 1) / spc;
    for (int b0 = 0; b0 < nchunks && !rv; b0 += EXR_BATCH) {
        int nb = nchunks - b0 < EXR_BATCH ? nchunks - b0 : EXR_BATCH;
        for (int i = 0; i < nb && !rv; i++) {
            slot[i].rv = EXR_ERR_SUCCESS;
            rv = exr_write_scanline_chunk_info(ctx, part, (b0 + i) * spc, &slot[i].ci);
        }
        if (rv) break;
#pragma omp parallel for schedule(dynamic, 1)
        for (int i = 0; i < nb; i++) {
            exr_slot *s = &slot[i];
            exr_result_t r = s->have ? exr_encoding_update(ctx, part, &s->ci, &s->enc)
                                     : exr_encoding_initialize(ctx, part, &s->ci, &s->enc);
            if (!r) {
                bind_channels(s->enc.channels, s->enc.channel_count, names, img->channels,
                              img->data, img->width, s->ci.start_y);
                if (!s->have) r = exr_encoding_choose_default_routines(ctx, part, &s->enc);
                s->have = 1;
            }
            if (!r) {
                s->enc.yield_until_ready_fn = NULL; /* written below, in order */
                s->enc.write_fn = NULL;
                r = exr_encoding_run(ctx, part, &s->enc);
            }
            s->rv = r;
        }
        for (int i = 0; i < nb && !rv; i++) {
            rv = slot[i].rv;
            if (!rv)
                rv = exr_write_scanline_chunk(ctx, part, slot[i].ci.start_y,
                                              slot[i].enc.compressed_buffer,
                                              slot[i].enc.compressed_bytes);
        }
    }
    for (int i = 0; i < EXR_BATCH; i++)
        if (slot[i].have) exr_encoding_destroy(ctx, &slot[i].enc);
    free(slot);
    return rv;
}

ss_status ss_exr_write_channels(const char *path, const ss_image *img, const char *const *names,
                                int use_half, ss_error *err) {
    if (!img || !img->data || img->width <= 0 || img->height <= 0 || img->channels < 1 ||
        img->channels > 64 || !names)
        return ss_error_set(err, SS_ERR_INPUT,
                            "%s: EXR needs a 1-64 channel image of positive size and names", path);
    ss_atomic_file af;
    ss_status st = ss_atomic_open(&af, path, err);
    if (st) return st;

    exr_io io = {.fd = fileno(af.fp), .msg = ""};
    exr_context_initializer_t init = make_init(&io);
    init.write_fn = io_write;
    exr_context_t ctx = NULL;
    int nch = img->channels, part = 0, spc = 1;
    exr_pixel_type_t pt = use_half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;

    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (!rv) rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (!rv)
        rv = exr_initialize_required_attr_simple(ctx, part, img->width, img->height,
                                                 EXR_COMPRESSION_ZIP);
    /* zlib level 1: a few % larger than the default 6, about a third of the time */
    if (!rv) rv = exr_set_zip_compression_level(ctx, part, SS_EXR_ZIP_LEVEL);
    for (int c = 0; c < nch && !rv; c++)
        rv = exr_add_channel(ctx, part, names[c], pt, EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (!rv) rv = exr_write_header(ctx);
    if (!rv) rv = exr_get_scanlines_per_chunk(ctx, part, &spc);
    if (!rv) rv = write_chunks(ctx, part, img, names, spc);
    exr_result_t rv2 = ctx ? exr_finish(&ctx) : EXR_ERR_SUCCESS; /* writes the offset table */
    if (!rv) rv = rv2;
    if (rv) {
        ss_atomic_abort(&af);
        return ss_error_set(err, SS_ERR_RUNTIME, "%s: cannot write EXR: %s", path,
                            io.write_errno ? strerror(io.write_errno) : why(&io, rv));
    }
    return ss_atomic_commit(&af, err);
}

/* Decodes part 0 of an open read context into a new image; NULL + err on failure. */
static ss_image *read_pixels(exr_context_t ctx, const char *path, exr_io *io,
                             const char *const *want, int nwant, ss_error *err) {
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *cl = NULL;
    exr_result_t rv = exr_get_storage(ctx, 0, &storage);
    if (!rv && storage != EXR_STORAGE_SCANLINE) {
        ss_error_set(err, SS_ERR_INPUT, "%s: %s EXR not supported (scanline only)", path,
                     storage == EXR_STORAGE_TILED ? "tiled" : "deep");
        return NULL;
    }
    if (!rv) rv = exr_get_data_window(ctx, 0, &dw);
    if (!rv) rv = exr_get_channels(ctx, 0, &cl);
    if (rv) {
        ss_error_set(err, SS_ERR_INPUT, "%s: bad EXR header: %s", path, why(io, rv));
        return NULL;
    }
    /* Pick the output layout from the channels present (subsampled ones do not count). */
    static const char order[] = "RGBAY";
    int has[5] = {0};
    for (int i = 0; i < cl->num_channels; i++) {
        const exr_attr_chlist_entry_t *e = &cl->entries[i];
        const char *p = e->name.length == 1 ? strchr(order, e->name.str[0]) : NULL;
        if (p && *p && e->x_sampling == 1 && e->y_sampling == 1) has[p - order] = 1;
    }
    int nch = (has[0] && has[1] && has[2]) ? 3 + has[3] : has[4] ? 1 + has[3] : 0;
    if (want) { /* the caller names the channels: each must be there */
        for (int k = 0; k < nwant; k++) {
            int found = 0;
            for (int i = 0; i < cl->num_channels; i++)
                found |= !strcmp(cl->entries[i].name.str, want[k]) &&
                         cl->entries[i].x_sampling == 1 && cl->entries[i].y_sampling == 1;
            if (!found) {
                ss_error_set(err, SS_ERR_INPUT, "%s: EXR has no channel '%s'", path, want[k]);
                return NULL;
            }
        }
        nch = nwant;
    }
    if (!nch) {
        ss_error_set(err, SS_ERR_INPUT, "%s: EXR has neither R,G,B nor Y channels", path);
        return NULL;
    }
    int64_t w64 = (int64_t)dw.max.x - dw.min.x + 1, h64 = (int64_t)dw.max.y - dw.min.y + 1;
    if (w64 <= 0 || h64 <= 0 || w64 > SS_IMAGE_MAX_SIDE || h64 > SS_IMAGE_MAX_SIDE) {
        ss_error_set(err, SS_ERR_INPUT, "%s: EXR data window %lldx%lld not supported", path,
                     (long long)w64, (long long)h64);
        return NULL;
    }
    if (ss_image_check_alloc(path, (long)w64, (long)h64, nch, err)) return NULL;
    ss_image *img = ss_image_create((int)w64, (int)h64, nch, err);
    if (!img) return NULL;

    const char *const *names = want ? want : NAMES[nch];
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int spc = 1, have_dec = 0;
    rv = exr_get_scanlines_per_chunk(ctx, 0, &spc);
    for (int y = dw.min.y; y <= dw.max.y && !rv; y += spc) {
        exr_chunk_info_t ci;
        rv = exr_read_scanline_chunk_info(ctx, 0, y, &ci);
        if (!rv)
            rv = have_dec ? exr_decoding_update(ctx, 0, &ci, &dec)
                          : exr_decoding_initialize(ctx, 0, &ci, &dec);
        if (rv) break;
        bind_channels(dec.channels, dec.channel_count, names, nch, img->data, img->width,
                      ci.start_y - dw.min.y);
        if (!have_dec) {
            have_dec = 1;
            rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
            /* NULL means uncompressed data is read straight into our (planar) pointers. */
            if (dec.unpack_and_convert_fn) dec.unpack_and_convert_fn = unpack_to_float;
        }
        if (!rv) rv = exr_decoding_run(ctx, 0, &dec);
    }
    if (have_dec) exr_decoding_destroy(ctx, &dec);
    if (rv) {
        ss_image_free(img);
        ss_error_set(err, SS_ERR_INPUT, "%s: corrupt or truncated EXR: %s", path, why(io, rv));
        return NULL;
    }
    return img;
}

static ss_image *exr_read_impl(const char *path, const char *const *want, int nwant, ss_error *err);
ss_image *ss_exr_read(const char *path, ss_error *err) { return exr_read_impl(path, NULL, 0, err); }
ss_image *ss_exr_read_channels(const char *path, const char *const *names, int n, ss_error *err) {
    if (!names || n < 1 || n > 64) {
        ss_error_set(err, SS_ERR_INPUT, "%s: 1-64 channel names needed", path);
        return NULL;
    }
    return exr_read_impl(path, names, n, err);
}

static ss_image *exr_read_impl(const char *path, const char *const *want, int nwant,
                               ss_error *err) {
    /* regular files only, and the open never blocks (named pipes) */
    exr_io io = {.fd = ss_input_open_fd(path, NULL, err), .msg = ""};
    if (io.fd < 0) return NULL;
    exr_context_initializer_t init = make_init(&io);
    init.read_fn = io_read;
    init.size_fn = io_size;
    init.flags = EXR_CONTEXT_FLAG_DISABLE_CHUNK_RECONSTRUCTION;
    exr_context_t ctx = NULL;
    ss_image *img = NULL;
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    if (rv)
        ss_error_set(err, SS_ERR_INPUT, "%s: not a readable OpenEXR file: %s", path, why(&io, rv));
    else
        img = read_pixels(ctx, path, &io, want, nwant, err);
    if (ctx) exr_finish(&ctx);
    close(io.fd);
    return img;
}
