/* The nodal-field file of the strip: recorder, writer and the field_input reader; see tc_fields.h.
 *
 * Byte order: every integer and double is written byte by byte, least significant first, from its value
 * (a double through its IEEE 754 bit pattern, which has the byte order of uint64_t on every target), so the
 * file is the same on any host.
 *
 * Portability: all of this is C11's standard library except creating a missing folder, for which C has no
 * function: mkdir (<sys/stat.h>, POSIX) or _mkdir (<direct.h>, Windows), and the process id in the name of
 * the temporary file, getpid (<unistd.h>) or _getpid (<process.h>), both behind #if defined(_WIN32).
 */
#if !defined(_WIN32) && !defined(_POSIX_C_SOURCE)
#define _POSIX_C_SOURCE 200809L /* mkdir, getpid */
#endif

#include "tc_fields.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <direct.h>
#include <process.h>
#else
#include <sys/stat.h>
#include <unistd.h>
#endif

#include "tc_json.h"
#include "tc_npz.h"

/* zipfile.ZIP64_LIMIT: sizes and offsets above it go to ZIP64 fields (a test build lowers it) */
#ifndef TC_FIELDS_ZIP64_LIMIT
#define TC_FIELDS_ZIP64_LIMIT ((((uint64_t)1) << 31) - 1)
#endif

#define N_MEMBERS 7
#define PATH_REPR_SIZE 1024
#define DETAIL_SIZE 768

/* ---- small helpers --------------------------------------------------------------------------------------- */

const char *tc_format_g(double x, char buf[TC_FORMAT_G_SIZE]) {
    if (isnan(x)) return strcpy(buf, "nan");
    if (isinf(x)) return strcpy(buf, x > 0 ? "inf" : "-inf");
    /* Python's 'g' and C's %g agree for finite values (precision 6, trailing zeros dropped, exponent of at
     * least two digits); only the decimal point may differ, when the host has set a C locale */
    char tmp[TC_FORMAT_G_SIZE];
    snprintf(tmp, sizeof tmp, "%g", x);
    size_t k = 0;
    for (const char *p = tmp; *p != '\0' && k + 1 < TC_FORMAT_G_SIZE; ++p) {
        if ((*p >= '0' && *p <= '9') || *p == '-' || *p == '+' || *p == 'e') buf[k++] = *p;
        else if (k == 0 || buf[k - 1] != '.') buf[k++] = '.'; /* a (possibly multibyte) decimal point */
    }
    buf[k] = '\0';
    return buf;
}

static char *copy_string(const char *s) {
    size_t n = strlen(s) + 1;
    char *c = malloc(n);
    if (c != NULL) memcpy(c, s, n);
    return c;
}

/* An operating-system error as Python's OSError prints it: "[Errno 2] No such file or directory: 'path'". */
static void os_error(char *buf, size_t size, int err, const char *file) {
    char fr[PATH_REPR_SIZE];
    tc_repr_string(file, fr, sizeof fr);
    if (err != 0) snprintf(buf, size, "[Errno %d] %s: %s", err, strerror(err), fr);
    else snprintf(buf, size, "input/output error on %s", fr);
}

static void put16(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)(v & 0xFFu);
    p[1] = (unsigned char)(v >> 8 & 0xFFu);
}
static void put32(unsigned char *p, uint32_t v) {
    for (int k = 0; k < 4; ++k) p[k] = (unsigned char)(v >> (8 * k) & 0xFFu);
}
static void put64(unsigned char *p, uint64_t v) {
    for (int k = 0; k < 8; ++k) p[k] = (unsigned char)(v >> (8 * k) & 0xFFu);
}
static double get_f8(const unsigned char *p) {
    uint64_t bits = 0;
    for (int k = 7; k >= 0; --k) bits = bits << 8 | p[k];
    double x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

/* ---- the writer: np.savez's zip archive of .npy members ------------------------------------------------- */

enum { KIND_F8, KIND_TEXT };

typedef struct member {
    char name[16];           /* "time.npy" */
    unsigned char head[256]; /* the .npy header (magic, version, length, dict, padding, newline) */
    size_t head_len;
    int kind;
    const double *values;    /* KIND_F8: count doubles */
    const char *text;        /* KIND_TEXT: text_len ASCII characters, stored as UTF-32LE code units (count >= 1) */
    size_t text_len;
    uint64_t count;
    uint64_t size;           /* head_len + the data's bytes */
    uint32_t crc;
    uint64_t offset;         /* of its local header */
} member;

typedef struct writer {
    FILE *f;
    uint64_t pos;
    int failed, err;         /* a write failed; errno then (0 if unknown) */
    uint32_t crc_table[256];
    size_t used;
    unsigned char buf[1 << 16];
} writer;

/* numpy.lib.format._write_array_header with version (1, 0): the dict's repr with sorted keys, room to grow
 * the first axis to 21 digits, spaces to a multiple of 64 bytes, a newline. */
static void npy_header(member *mb, const char *descr, int ndim, uint64_t d0, uint64_t d1) {
    char dict[200], shape[64];
    if (ndim == 0) snprintf(shape, sizeof shape, "()");
    else if (ndim == 1) snprintf(shape, sizeof shape, "(%llu,)", (unsigned long long)d0);
    else snprintf(shape, sizeof shape, "(%llu, %llu)", (unsigned long long)d0, (unsigned long long)d1);
    int len = snprintf(dict, sizeof dict, "{'descr': '%s', 'fortran_order': False, 'shape': %s, }", descr, shape);
    size_t n = (size_t)len;
    if (ndim > 0) {
        char d0_text[24];
        size_t digits = (size_t)snprintf(d0_text, sizeof d0_text, "%llu", (unsigned long long)d0);
        for (size_t k = digits; k < 21; ++k) dict[n++] = ' ';
    }
    size_t hlen = n + 1;                  /* with the newline */
    size_t pad = 64 - (10 + hlen) % 64;   /* magic (6) + version (2) + length (2) + header aligned to 64 */
    unsigned char *h = mb->head;
    memcpy(h, "\x93NUMPY\x01\x00", 8);
    put16(h + 8, (uint32_t)(hlen + pad));
    memcpy(h + 10, dict, n);
    memset(h + 10 + n, ' ', pad);
    h[10 + n + pad] = '\n';
    mb->head_len = 10 + hlen + pad;
}

static void set_f8(member *mb, const char *key, const double *values, int ndim, uint64_t d0, uint64_t d1) {
    snprintf(mb->name, sizeof mb->name, "%s.npy", key);
    npy_header(mb, "<f8", ndim, d0, d1);
    mb->kind = KIND_F8;
    mb->values = values;
    mb->count = ndim == 2 ? d0 * d1 : d0;
    mb->size = mb->head_len + 8 * mb->count;
}

static void set_text(member *mb, const char *key, const char *text) {
    char descr[32];
    size_t n = strlen(text);
    snprintf(mb->name, sizeof mb->name, "%s.npy", key);
    snprintf(descr, sizeof descr, "<U%llu", (unsigned long long)(n > 0 ? n : 1)); /* np.array('') is '<U1' */
    npy_header(mb, descr, 0, 0, 0);
    mb->kind = KIND_TEXT;
    mb->text = text;
    mb->text_len = n;
    mb->count = n > 0 ? n : 1;
    mb->size = mb->head_len + 4 * mb->count;
}

/* Elements [first, first + count) of a member's data as little-endian bytes into out (8 or 4 per element). */
#define CHUNK 512
static size_t encode(const member *mb, uint64_t first, size_t count, unsigned char out[8 * CHUNK]) {
    if (mb->kind == KIND_F8) {
        for (size_t i = 0; i < count; ++i) {
            uint64_t bits;
            memcpy(&bits, &mb->values[first + i], sizeof bits);
            put64(out + 8 * i, bits);
        }
        return 8 * count;
    }
    for (size_t i = 0; i < count; ++i)
        put32(out + 4 * i, first + i < mb->text_len ? (uint32_t)(unsigned char)mb->text[first + i] : 0u);
    return 4 * count;
}

static uint32_t crc_update(const uint32_t table[256], uint32_t crc, const unsigned char *p, size_t n) {
    for (size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
    return crc;
}

static uint32_t member_crc(const writer *w, const member *mb) {
    unsigned char chunk[8 * CHUNK];
    uint32_t crc = crc_update(w->crc_table, 0xFFFFFFFFu, mb->head, mb->head_len);
    for (uint64_t i = 0; i < mb->count; i += CHUNK) {
        size_t k = mb->count - i < CHUNK ? (size_t)(mb->count - i) : CHUNK;
        crc = crc_update(w->crc_table, crc, chunk, encode(mb, i, k, chunk));
    }
    return crc ^ 0xFFFFFFFFu;
}

static void flush(writer *w) {
    if (w->used > 0 && !w->failed) {
        errno = 0;
        if (fwrite(w->buf, 1, w->used, w->f) != w->used) {
            w->failed = 1;
            w->err = errno;
        }
    }
    w->used = 0;
}

static void put(writer *w, const void *data, size_t n) {
    const unsigned char *p = data;
    w->pos += n;
    while (n > 0) {
        if (w->used == sizeof w->buf) flush(w);
        size_t k = sizeof w->buf - w->used < n ? sizeof w->buf - w->used : n;
        memcpy(w->buf + w->used, p, k);
        w->used += k;
        p += k;
        n -= k;
    }
}

/* Local header + data of one member, as zipfile writes it for ZipFile.open(name, 'w', force_zip64=True) on
 * a seekable file: version 4.5, sizes 0xFFFFFFFF and a ZIP64 extra field with both sizes. */
static void write_member(writer *w, member *mb) {
    unsigned char h[30 + 16 + 20], chunk[8 * CHUNK];
    size_t name_len = strlen(mb->name);
    mb->offset = w->pos;
    memcpy(h, "PK\x03\x04", 4);
    put16(h + 4, 45);           /* version needed to extract: 4.5 (ZIP64) */
    put16(h + 6, 0);            /* flags */
    put16(h + 8, 0);            /* stored */
    put16(h + 10, 0);           /* DOS time 00:00:00 */
    put16(h + 12, 1u << 5 | 1); /* DOS date 1980-01-01, ZipInfo's default */
    put32(h + 14, mb->crc);
    put32(h + 18, 0xFFFFFFFFu);
    put32(h + 22, 0xFFFFFFFFu);
    put16(h + 26, (uint32_t)name_len);
    put16(h + 28, 20);
    memcpy(h + 30, mb->name, name_len);
    unsigned char *x = h + 30 + name_len;
    put16(x, 1);
    put16(x + 2, 16);
    put64(x + 4, mb->size);
    put64(x + 12, mb->size);
    put(w, h, 30 + name_len + 20);
    put(w, mb->head, mb->head_len);
    for (uint64_t i = 0; i < mb->count; i += CHUNK) {
        size_t k = mb->count - i < CHUNK ? (size_t)(mb->count - i) : CHUNK;
        put(w, chunk, encode(mb, i, k, chunk));
    }
}

/* Central directory and end records as zipfile._write_end_record writes them. */
static void write_directory(writer *w, const member *mb, size_t n_members) {
    const uint64_t limit = TC_FIELDS_ZIP64_LIMIT;
    uint64_t cd_offset = w->pos;
    for (size_t i = 0; i < n_members; ++i) {
        unsigned char e[46 + 16 + 28];
        size_t name_len = strlen(mb[i].name);
        uint64_t extra[3];
        size_t n_extra = 0;
        int big = mb[i].size > limit, far = mb[i].offset > limit;
        if (big) {
            extra[n_extra++] = mb[i].size;
            extra[n_extra++] = mb[i].size;
        }
        if (far) extra[n_extra++] = mb[i].offset;
        size_t extra_len = n_extra > 0 ? 4 + 8 * n_extra : 0;
        memcpy(e, "PK\x01\x02", 4);
        e[4] = 45;                        /* made by version 4.5 */
        e[5] = 3;                         /* on Unix (what np.savez writes on Linux and macOS) */
        put16(e + 6, 45);                 /* version needed: 4.5 (set by the ZIP64 local header) */
        put16(e + 8, 0);
        put16(e + 10, 0);
        put16(e + 12, 0);
        put16(e + 14, 1u << 5 | 1);
        put32(e + 16, mb[i].crc);
        put32(e + 20, big ? 0xFFFFFFFFu : (uint32_t)mb[i].size);
        put32(e + 24, big ? 0xFFFFFFFFu : (uint32_t)mb[i].size);
        put16(e + 28, (uint32_t)name_len);
        put16(e + 30, (uint32_t)extra_len);
        put16(e + 32, 0);                 /* comment */
        put16(e + 34, 0);                 /* disk */
        put16(e + 36, 0);                 /* internal attributes */
        put32(e + 38, 0600u << 16);       /* external: -rw------- */
        put32(e + 42, far ? 0xFFFFFFFFu : (uint32_t)mb[i].offset);
        memcpy(e + 46, mb[i].name, name_len);
        unsigned char *x = e + 46 + name_len;
        if (n_extra > 0) {
            put16(x, 1);
            put16(x + 2, (uint32_t)(8 * n_extra));
            for (size_t k = 0; k < n_extra; ++k) put64(x + 4 + 8 * k, extra[k]);
        }
        put(w, e, 46 + name_len + extra_len);
    }
    uint64_t cd_end = w->pos, cd_size = cd_end - cd_offset;
    if (n_members > 0xFFFF || cd_offset > limit || cd_size > limit) {
        unsigned char r[56 + 20];
        memcpy(r, "PK\x06\x06", 4);
        put64(r + 4, 44);
        put16(r + 12, 45);
        put16(r + 14, 45);
        put32(r + 16, 0);
        put32(r + 20, 0);
        put64(r + 24, n_members);
        put64(r + 32, n_members);
        put64(r + 40, cd_size);
        put64(r + 48, cd_offset);
        memcpy(r + 56, "PK\x06\x07", 4);
        put32(r + 60, 0);
        put64(r + 64, cd_end);
        put32(r + 72, 1);
        put(w, r, sizeof r);
    }
    unsigned char end[22];
    memcpy(end, "PK\x05\x06", 4);
    put16(end + 4, 0);
    put16(end + 6, 0);
    put16(end + 8, (uint32_t)(n_members < 0xFFFF ? n_members : 0xFFFF));
    put16(end + 10, (uint32_t)(n_members < 0xFFFF ? n_members : 0xFFFF));
    put32(end + 12, (uint32_t)(cd_size < 0xFFFFFFFFu ? cd_size : 0xFFFFFFFFu));
    put32(end + 16, (uint32_t)(cd_offset < 0xFFFFFFFFu ? cd_offset : 0xFFFFFFFFu));
    put16(end + 20, 0);
    put(w, end, sizeof end);
    flush(w);
}

static int is_separator(char c) {
#if defined(_WIN32)
    return c == '/' || c == '\\';
#else
    return c == '/';
#endif
}

static int make_folder(const char *folder) {
#if defined(_WIN32)
    return _mkdir(folder);
#else
    return mkdir(folder, 0777);
#endif
}

static long process_id(void) {
#if defined(_WIN32)
    return (long)_getpid();
#else
    return (long)getpid();
#endif
}

/* Path.parent.mkdir(parents=True, exist_ok=True): every folder on the way, from the top. Failures are kept
 * (the last one other than "exists"), not returned: whether the folder is usable shows when the temporary
 * file is opened, and the kept failure then explains why it is not. */
static void make_parents(char *path, size_t dir_len, int *err, size_t *err_len) {
    for (size_t i = 1; i < dir_len; ++i) {
        if (!is_separator(path[i]) || is_separator(path[i - 1]) || path[i - 1] == ':') continue;
        char c = path[i];
        path[i] = '\0'; /* the folder path[0..i), then the separator back */
        errno = 0;
        if (make_folder(path) != 0 && errno != EEXIST) {
            *err = errno;
            *err_len = i;
        }
        path[i] = c;
    }
}

int tc_fields_write(const char *path, size_t n_rows, size_t n_nodes, const double *time, const double *X,
                    const double *beta, const double *U, const double *contact, const double window[2],
                    const char *metadata_json, tc_msg msg) {
    char pr[PATH_REPR_SIZE], reason[DETAIL_SIZE + PATH_REPR_SIZE];
    if (path == NULL || path[0] == '\0') return tc_fail(msg, TC_ERROR, "field_output: no file name given");
    tc_repr_string(path, pr, sizeof pr);
    if (X == NULL || window == NULL || metadata_json == NULL ||
        (n_rows > 0 && (time == NULL || beta == NULL || U == NULL || contact == NULL)))
        return tc_fail(msg, TC_ERROR, "field_output = %s cannot be written: an array is missing (NULL)", pr);
    if (n_nodes > 0 && n_rows > SIZE_MAX / 8 / n_nodes)
        return tc_fail(msg, TC_ERROR, "field_output = %s cannot be written: %zu rows of %zu nodes are too many", pr,
                       n_rows, n_nodes);

    /* the folder part of path (with its last separator) and the temporary file beside the target */
    size_t len = strlen(path), dir_len = len;
    while (dir_len > 0 && !is_separator(path[dir_len - 1])) --dir_len;
    if (dir_len == len) return tc_fail(msg, TC_ERROR, "field_output = %s names a folder, not a file", pr);
    size_t tmp_size = len + 64;
    char *tmp = malloc(tmp_size);
    writer *w = malloc(sizeof *w);
    if (tmp == NULL || w == NULL) {
        free(tmp);
        free(w);
        return tc_fail(msg, TC_NOMEM, "field_output = %s cannot be written: out of memory", pr);
    }
    /* Python's ".NAME.PID.partial", with this writer's address: two writers in one process differ too */
    snprintf(tmp, tmp_size, "%.*s.%s.%ld.%llx.partial", (int)dir_len, path, path + dir_len, process_id(),
             (unsigned long long)(uintptr_t)(void *)w);

    /* the members in write_fields' order */
    member mb[N_MEMBERS];
    memset(mb, 0, sizeof mb);
    set_f8(&mb[0], "time", time, 1, n_rows, 0);
    set_f8(&mb[1], "X", X, 1, n_nodes, 0);
    set_f8(&mb[2], "beta", beta, 2, n_rows, n_nodes);
    set_f8(&mb[3], "U", U, 2, n_rows, n_nodes);
    set_f8(&mb[4], "contact", contact, 2, n_rows, n_nodes);
    set_f8(&mb[5], "window", window, 1, 2, 0);
    set_text(&mb[6], "metadata", metadata_json);

    memset(w, 0, sizeof *w);
    for (uint32_t i = 0; i < 256; ++i) { /* CRC-32 (ISO 3309, reflected polynomial 0xEDB88320), as zlib */
        uint32_t c = i;
        for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        w->crc_table[i] = c;
    }
    for (size_t i = 0; i < N_MEMBERS; ++i) mb[i].crc = member_crc(w, &mb[i]);

    /* the folders, then the temporary file; tmp starts with path's folder part, which make_parents walks */
    int mkdir_err = 0, rc = TC_OK;
    size_t mkdir_len = 0;
    make_parents(tmp, dir_len, &mkdir_err, &mkdir_len);
    errno = 0;
    w->f = fopen(tmp, "wb");
    if (w->f == NULL) {
        int open_err = errno;
        if (mkdir_err != 0) { /* a folder that could not be made is the reason, as Python's mkdir reports it */
            tmp[mkdir_len] = '\0';
            os_error(reason, sizeof reason, mkdir_err, tmp);
        } else {
            os_error(reason, sizeof reason, open_err, tmp);
        }
        rc = tc_fail(msg, TC_ERROR, "field_output = %s cannot be written: %s", pr, reason);
    }
    if (rc == TC_OK) {
        for (size_t i = 0; i < N_MEMBERS; ++i) write_member(w, &mb[i]);
        write_directory(w, mb, N_MEMBERS);
        errno = 0;
        if (fclose(w->f) != 0 && !w->failed) {
            w->failed = 1;
            w->err = errno;
        }
        if (w->failed) {
            os_error(reason, sizeof reason, w->err, tmp);
            rc = tc_fail(msg, TC_ERROR, "field_output = %s cannot be written: %s", pr, reason);
            remove(tmp);
        }
    }
    if (rc == TC_OK) {
#if defined(_WIN32)
        remove(path); /* rename does not replace an existing file on Windows */
#endif
        errno = 0;
        if (rename(tmp, path) != 0) {
            os_error(reason, sizeof reason, errno, path);
            rc = tc_fail(msg, TC_ERROR, "field_output = %s cannot be written: %s", pr, reason);
            remove(tmp);
        }
    }
    free(w);
    free(tmp);
    return rc;
}

/* ---- the recorder ---------------------------------------------------------------------------------------- */

struct tc_field_recorder {
    char *path;
    double interval;
    size_t m;         /* nodes per row */
    double *X;        /* m values */
    double window[2];
    char *metadata;   /* the JSON text (ASCII) */
    size_t n, cap;    /* rows recorded, rows allocated */
    double *time;     /* cap values */
    double *rows[3];  /* beta, U, contact: cap x m each, row-major (the first n rows are the file's arrays) */
};

void tc_field_recorder_free(tc_field_recorder *r) {
    if (r == NULL) return;
    free(r->path);
    free(r->X);
    free(r->metadata);
    free(r->time);
    for (int k = 0; k < 3; ++k) free(r->rows[k]);
    free(r);
}

int tc_field_recorder_create(const char *path, double interval, size_t n_nodes, const double *X,
                             const double window[2], const char *metadata_json, tc_field_recorder **out,
                             tc_msg msg) {
    char buf[TC_REPR_SIZE];
    if (out == NULL) return tc_fail(msg, TC_ERROR, "tc_field_recorder_create needs somewhere to put the recorder");
    *out = NULL;
    if (isnan(interval) || interval < 0)
        return tc_fail(msg, TC_ERROR, "field_output_interval = %s s must be >= 0", tc_repr_double(interval, buf));
    if (isinf(interval)) /* the FMU's parameter check (check_finite) refuses it before FieldRecorder sees it */
        return tc_fail(msg, TC_ERROR, "field_output_interval = %s is not finite; a finite number is required",
                       tc_repr_double(interval, buf));
    if (path == NULL || path[0] == '\0') return tc_fail(msg, TC_ERROR, "field_output: no file name given");
    if (n_nodes == 0 || X == NULL || window == NULL)
        return tc_fail(msg, TC_ERROR, "field_output needs the mesh: n_nodes >= 1 node coordinates X and the window");
    if (metadata_json == NULL) return tc_fail(msg, TC_ERROR, "field_output needs the metadata JSON text");
    size_t meta_n = strlen(metadata_json);
    for (size_t i = 0; i < meta_n; ++i)
        if ((unsigned char)metadata_json[i] >= 0x80)
            return tc_fail(msg, TC_ERROR, "field_output metadata is not ASCII at byte %zu (json.dumps writes \\u "
                                          "escapes for other characters)", i);
    char detail[DETAIL_SIZE];
    tc_msg d = {detail, sizeof detail};
    if (tc_json_check_object(metadata_json, meta_n, d) != TC_OK)
        return tc_fail(msg, TC_ERROR, "field_output metadata is not a JSON object: %s", detail);
    if (n_nodes > SIZE_MAX / sizeof(double) / 16)
        return tc_fail(msg, TC_ERROR, "field_output: %zu nodes are too many", n_nodes);

    tc_field_recorder *r = calloc(1, sizeof *r);
    if (r == NULL) return tc_fail(msg, TC_NOMEM, "field_output: out of memory for the recorder");
    r->path = copy_string(path);
    r->X = malloc(n_nodes * sizeof *r->X);
    r->metadata = copy_string(metadata_json);
    if (r->path == NULL || r->X == NULL || r->metadata == NULL) {
        tc_field_recorder_free(r);
        return tc_fail(msg, TC_NOMEM, "field_output: out of memory for the recorder");
    }
    r->interval = interval;
    r->m = n_nodes;
    memcpy(r->X, X, n_nodes * sizeof *r->X);
    r->window[0] = window[0];
    r->window[1] = window[1];
    *out = r;
    return TC_OK;
}

/* Room for one more row: capacity doubled (16 rows first). The arrays are reallocated one by one and the
 * capacity raised only when all four have grown, so a failure leaves a consistent recorder. */
static int grow(tc_field_recorder *r) {
    if (r->n < r->cap) return TC_OK;
    size_t cap = r->cap == 0 ? 16 : r->cap;
    if (r->cap > 0) {
        if (cap > SIZE_MAX / 2 / sizeof(double) / r->m) return TC_NOMEM;
        cap *= 2;
    }
    double *t = realloc(r->time, cap * sizeof *t);
    if (t == NULL) return TC_NOMEM;
    r->time = t;
    for (int k = 0; k < 3; ++k) {
        double *a = realloc(r->rows[k], cap * r->m * sizeof *a);
        if (a == NULL) return TC_NOMEM;
        r->rows[k] = a;
    }
    r->cap = cap;
    return TC_OK;
}

int tc_field_recorder_record(tc_field_recorder *r, double t, const double *beta, const double *U,
                             const double *contact, int force, tc_msg msg) {
    if (r == NULL || beta == NULL || U == NULL || contact == NULL)
        return tc_fail(msg, TC_ERROR, "tc_field_recorder_record needs a recorder and the three fields");
    if (!force && r->n > 0 && t < r->time[r->n - 1] + r->interval * (1.0 - 1e-9)) return TC_OK;
    if (grow(r) != TC_OK)
        return tc_fail(msg, TC_NOMEM, "field_output: out of memory for row %zu (%zu nodes)", r->n + 1, r->m);
    const double *src[3] = {beta, U, contact};
    for (int k = 0; k < 3; ++k) memcpy(r->rows[k] + r->n * r->m, src[k], r->m * sizeof(double));
    r->time[r->n++] = t;
    return TC_OK;
}

void tc_field_recorder_truncate(tc_field_recorder *r, double t) {
    if (r == NULL) return;
    while (r->n > 0 && r->time[r->n - 1] > t * (1.0 + 1e-12) + 1e-15) --r->n;
}

int tc_field_recorder_write(const tc_field_recorder *r, tc_msg msg) {
    if (r == NULL) return tc_fail(msg, TC_ERROR, "tc_field_recorder_write needs a recorder");
    return tc_fields_write(r->path, r->n, r->m, r->time, r->X, r->rows[0], r->rows[1], r->rows[2], r->window,
                           r->metadata, msg);
}

int tc_field_recorder_finish(tc_field_recorder *r, double t, const double *beta, const double *U,
                             const double *contact, tc_msg msg) {
    if (r == NULL) return tc_fail(msg, TC_ERROR, "tc_field_recorder_finish needs a recorder");
    if (r->n == 0 || t > r->time[r->n - 1]) {
        int rc = tc_field_recorder_record(r, t, beta, U, contact, 1, msg);
        if (rc != TC_OK) return rc;
    }
    return tc_field_recorder_write(r, msg);
}

size_t tc_field_recorder_rows(const tc_field_recorder *r) { return r != NULL ? r->n : 0; }

double tc_field_recorder_last_time(const tc_field_recorder *r) {
    return r != NULL && r->n > 0 ? r->time[r->n - 1] : NAN;
}

/* ---- the reader: read_initial_beta ------------------------------------------------------------------------ */

/* numpy.lib.format.BUFFER_SIZE: read_array reads the data of a zip member in chunks of this many bytes */
#define NPY_BUFFER_SIZE ((uint64_t)1 << 18)

/* The whole file; errors as Python's open() and read() report them. */
static int read_file(const char *path, unsigned char **data, size_t *size, char *reason, size_t reason_size) {
    errno = 0;
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        os_error(reason, reason_size, errno != 0 ? errno : ENOENT, path);
        return TC_ERROR;
    }
    size_t cap = (size_t)1 << 16, used = 0;
    unsigned char *buf = malloc(cap);
    int rc = TC_OK;
    if (buf == NULL) rc = TC_NOMEM;
    while (rc == TC_OK) {
        if (used == cap) {
            unsigned char *bigger = cap <= SIZE_MAX / 2 ? realloc(buf, cap * 2) : NULL;
            if (bigger == NULL) {
                rc = TC_NOMEM;
                break;
            }
            buf = bigger;
            cap *= 2;
        }
        errno = 0;
        used += fread(buf + used, 1, cap - used, f);
        if (ferror(f)) { /* a folder, on POSIX systems: fopen succeeds, reading fails with EISDIR */
            os_error(reason, reason_size, errno, path);
            rc = TC_ERROR;
        } else if (feof(f)) {
            break;
        }
    }
    fclose(f);
    if (rc == TC_NOMEM) snprintf(reason, reason_size, "out of memory reading the file");
    if (rc != TC_OK) {
        free(buf);
        return rc;
    }
    *data = buf;
    *size = used;
    return TC_OK;
}

/* One float64 array of the file: its header and where its data start. */
typedef struct f8_array {
    tc_npy npy;
    const unsigned char *bytes;
} f8_array;

/* NpzFile[key] then np.array(..., dtype=float), with the checks the native reader can make. */
static int load_f8(const tc_zip *zip, const char *key, f8_array *a, tc_msg d) {
    char member_name[32];
    tc_zip_member m;
    int rc;
    snprintf(member_name, sizeof member_name, "%s.npy", key);
    if (!tc_zip_has(zip, member_name)) return tc_fail(d, TC_ERROR, "'%s is not a file in the archive'", key);
    if ((rc = tc_zip_find(zip, member_name, &m, d)) != TC_OK) return rc;
    if ((rc = tc_npy_parse(zip->data + m.offset, m.size, member_name, &a->npy, d)) != TC_OK) return rc;
    if (strcmp(a->npy.descr, "<f8") != 0)
        return tc_fail(d, TC_ERROR, "'%s' has dtype '%s'; a field file holds '<f8' (little-endian float64)",
                       member_name, a->npy.descr);
    uint64_t avail = m.size - a->npy.data_offset; /* tc_npy_parse checked data_offset <= m.size */
    if (a->npy.count > avail / 8) {
        /* numpy's message: the first chunk of NPY_BUFFER_SIZE bytes that comes out short */
        uint64_t need = a->npy.count <= UINT64_MAX / 8 ? 8 * a->npy.count : UINT64_MAX;
        uint64_t k = avail / NPY_BUFFER_SIZE;
        uint64_t expected = need - k * NPY_BUFFER_SIZE < NPY_BUFFER_SIZE ? need - k * NPY_BUFFER_SIZE : NPY_BUFFER_SIZE;
        return tc_fail(d, TC_ERROR, "EOF: reading array data, expected %llu bytes got %llu",
                       (unsigned long long)expected, (unsigned long long)(avail - k * NPY_BUFFER_SIZE));
    }
    a->bytes = zip->data + m.offset + a->npy.data_offset;
    return TC_OK;
}

/* np.isclose(x, y, rtol=0, atol=1e-12): |x - y| <= atol with y finite, or x == y (infinities) */
static int close_to(double x, double y) { return (fabs(x - y) <= 1e-12 && isfinite(y)) || x == y; }

int tc_field_read_initial_beta(const char *path, size_t n_nodes, const double *X, double *beta_out, tc_msg msg) {
    char pr[PATH_REPR_SIZE], detail[DETAIL_SIZE + PATH_REPR_SIZE];
    tc_msg d = {detail, sizeof detail};
    if (path == NULL) return tc_fail(msg, TC_ERROR, "field_input: no file name given");
    tc_repr_string(path, pr, sizeof pr);
    if (n_nodes == 0 || X == NULL || beta_out == NULL)
        return tc_fail(msg, TC_ERROR, "field_input = %s: the strip's mesh (n_nodes >= 1, X) and room for beta are "
                                      "needed", pr);
    unsigned char *data = NULL;
    size_t size = 0;
    int rc = read_file(path, &data, &size, detail, sizeof detail);
    if (rc != TC_OK) return tc_fail(msg, rc, "field_input = %s cannot be read as a field_output file: %s", pr, detail);

    /* np.load decides by the first bytes */
    static const unsigned char NPY_MAGIC[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
    f8_array xa, ba;
    tc_zip zip;
    if (size == 0) {
        rc = tc_fail(d, TC_ERROR, "No data left in file");
    } else if (size < 4 || (memcmp(data, "PK\x03\x04", 4) != 0 && memcmp(data, "PK\x05\x06", 4) != 0)) {
        if (size >= 6 && memcmp(data, NPY_MAGIC, 6) == 0)
            rc = tc_fail(d, TC_ERROR, "it holds one .npy array, not an .npz archive of arrays");
        else
            rc = tc_fail(d, TC_ERROR, "This file contains pickled (object) data. If you trust the file you can load it "
                                      "unsafely using the `allow_pickle=` keyword argument or `pickle.load()`.");
    } else if ((rc = tc_zip_open(&zip, data, size, d)) == TC_OK && (rc = load_f8(&zip, "X", &xa, d)) == TC_OK) {
        rc = load_f8(&zip, "beta", &ba, d);
    }
    if (rc != TC_OK) {
        free(data);
        return tc_fail(msg, rc, "field_input = %s cannot be read as a field_output file: %s", pr, detail);
    }

    /* read_initial_beta's checks */
    uint64_t xs = xa.npy.count;
    if (ba.npy.ndim != 2 || ba.npy.shape[0] < 1 || ba.npy.shape[1] != xs) {
        char shape[128];
        tc_npy_shape_repr(&ba.npy, shape, sizeof shape);
        free(data);
        return tc_fail(msg, TC_ERROR, "field_input = %s: beta has shape %s, X has %llu nodes", pr, shape,
                       (unsigned long long)xs);
    }
    int same = xa.npy.ndim == 1 && xs == n_nodes;
    for (size_t i = 0; same && i < n_nodes; ++i) same = close_to(get_f8(xa.bytes + 8 * i), X[i]);
    if (!same) {
        char a[TC_FORMAT_G_SIZE], b[TC_FORMAT_G_SIZE], c[TC_FORMAT_G_SIZE], e[TC_FORMAT_G_SIZE], range[80];
        if (xs > 0)
            snprintf(range, sizeof range, " over [%s, %s] m", tc_format_g(get_f8(xa.bytes), a),
                     tc_format_g(get_f8(xa.bytes + 8 * (xs - 1)), b));
        else
            range[0] = '\0'; /* Python's Xf[0] would raise IndexError here */
        rc = tc_fail(msg, TC_ERROR, "field_input = %s was written for another mesh (%llu nodes%s; this strip has %zu "
                                    "nodes over [%s, %s] m): use the same geometry and n_elements",
                     pr, (unsigned long long)xs, range, n_nodes, tc_format_g(X[0], c), tc_format_g(X[n_nodes - 1], e));
        free(data);
        return rc;
    }
    /* beta[-1]: row n - 1 of an (n, m) array, in either storage order */
    uint64_t n = ba.npy.shape[0];
    for (size_t j = 0; j < n_nodes; ++j) {
        uint64_t at = ba.npy.fortran_order ? (uint64_t)j * n + (n - 1) : (n - 1) * n_nodes + j;
        beta_out[j] = get_f8(ba.bytes + 8 * at);
    }
    free(data);
    return TC_OK;
}
