/* Reader of the array file (tc_arrays.h; the layout is in components/native/resource_io/array_file.py). */
#include "tc_arrays.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAGIC "TCARRAYS"
#define VERSION 1u
#define MAX_FILE_SIZE ((size_t)1 << 30) /* a sanity bound: the shipped table's file is 180 kB */

/* little-endian unsigned integer of k bytes */
static uint64_t le(const unsigned char *p, int k) {
    uint64_t v = 0;
    for (int i = k - 1; i >= 0; --i) v = v << 8 | p[i];
    return v;
}

static int read_file(const char *path, const char *what, unsigned char **data, size_t *size, tc_msg msg) {
    errno = 0;
    FILE *f = fopen(path, "rb");
    if (f == NULL) return tc_fail(msg, TC_ERROR, "%s file not found: %s", what, path);
    size_t cap = (size_t)1 << 16, used = 0;
    unsigned char *buf = malloc(cap);
    int rc = buf == NULL ? tc_fail(msg, TC_NOMEM, "out of memory reading %s %s", what, path) : TC_OK;
    while (rc == TC_OK) {
        if (used == cap) {
            unsigned char *bigger = realloc(buf, cap * 2);
            if (bigger == NULL) {
                rc = tc_fail(msg, TC_NOMEM, "out of memory reading %s %s", what, path);
                break;
            }
            buf = bigger;
            cap *= 2;
        }
        used += fread(buf + used, 1, cap - used, f);
        if (ferror(f))
            rc = tc_fail(msg, TC_ERROR, "%s file %s cannot be read (is it a file?)", what, path);
        else if (used > MAX_FILE_SIZE)
            rc = tc_fail(msg, TC_ERROR, "%s %s is larger than 1 GiB; it is refused", what, path);
        else if (feof(f))
            break;
    }
    fclose(f);
    if (rc != TC_OK) {
        free(buf);
        return rc;
    }
    *data = buf;
    *size = used;
    return TC_OK;
}

void tc_arrays_free(tc_arrays *a) {
    if (a == NULL) return;
    for (size_t k = 0; k < a->n; ++k) {
        free(a->entries[k].values);
        free(a->entries[k].text);
    }
    free(a->entries);
    free(a);
}

const tc_array_entry *tc_arrays_find(const tc_arrays *a, const char *name) {
    for (size_t k = 0; k < a->n; ++k)
        if (strcmp(a->entries[k].name, name) == 0) return &a->entries[k];
    return NULL;
}

/* the entries of the bytes b[0..size) into a (entries allocated for count); detail says what is wrong */
static int parse(const unsigned char *b, size_t size, tc_arrays *a, uint32_t count, char *detail, size_t dsize) {
    size_t pos = 16;
#define NEED(k)                                                                                   \
    do {                                                                                          \
        if ((k) > size - pos) {                                                                   \
            snprintf(detail, dsize, "it ends inside entry %zu of %u", a->n + 1, (unsigned)count); \
            return TC_ERROR;                                                                      \
        }                                                                                         \
    } while (0)
    for (uint32_t k = 0; k < count; ++k) {
        tc_array_entry *e = &a->entries[a->n];
        NEED(2);
        const size_t len = (size_t)le(b + pos, 2);
        pos += 2;
        if (len == 0 || len > 255) {
            snprintf(detail, dsize, "entry %u has a name of %zu bytes (1 to 255 are allowed)", k + 1, len);
            return TC_ERROR;
        }
        NEED(len + 2);
        memcpy(e->name, b + pos, len);
        e->name[len] = '\0';
        pos += len;
        e->kind = b[pos];
        e->ndim = b[pos + 1];
        pos += 2;
        if ((e->kind != TC_ARRAY_FLOAT64 && e->kind != TC_ARRAY_TEXT) || e->ndim > TC_ARRAY_MAX_NDIM ||
            (e->kind == TC_ARRAY_TEXT && e->ndim != 0)) {
            snprintf(detail, dsize, "entry '%s' has kind %d with %d dimensions", e->name, e->kind, e->ndim);
            return TC_ERROR;
        }
        NEED(8 * (size_t)e->ndim + 8);
        uint64_t count_values = 1;
        for (int d = 0; d < e->ndim; ++d) {
            e->shape[d] = le(b + pos, 8);
            pos += 8;
            count_values = e->shape[d] != 0 && count_values > UINT64_MAX / e->shape[d] ? UINT64_MAX
                                                                                      : count_values * e->shape[d];
        }
        const uint64_t bytes = le(b + pos, 8);
        pos += 8;
        if (bytes > size - pos) {
            snprintf(detail, dsize, "entry '%s' is truncated", e->name);
            return TC_ERROR;
        }
        if (e->kind == TC_ARRAY_FLOAT64 && (count_values > UINT64_MAX / 8 || bytes != 8 * count_values)) {
            snprintf(detail, dsize, "entry '%s' has %llu bytes for its shape", e->name, (unsigned long long)bytes);
            return TC_ERROR;
        }
        e->count = e->kind == TC_ARRAY_FLOAT64 ? (size_t)count_values : (size_t)bytes;
        if (e->kind == TC_ARRAY_TEXT) {
            e->text = malloc(e->count + 1);
            if (e->text == NULL) return TC_NOMEM;
            memcpy(e->text, b + pos, e->count);
            e->text[e->count] = '\0';
        } else {
            e->values = malloc(e->count > 0 ? e->count * sizeof(double) : sizeof(double));
            if (e->values == NULL) return TC_NOMEM;
            for (size_t i = 0; i < e->count; ++i) {
                const uint64_t bits = le(b + pos + 8 * i, 8); /* IEEE 754 binary64, the byte order of uint64_t */
                memcpy(&e->values[i], &bits, sizeof bits);
            }
        }
        pos += (size_t)bytes;
        a->n += 1;
        for (size_t j = 0; j + 1 < a->n; ++j)
            if (strcmp(a->entries[j].name, e->name) == 0) {
                snprintf(detail, dsize, "entry '%s' appears twice", e->name);
                return TC_ERROR;
            }
    }
#undef NEED
    return TC_OK;
}

int tc_arrays_read(const char *path, const char *what, tc_arrays **out, tc_msg msg) {
    *out = NULL;
    unsigned char *data = NULL;
    size_t size = 0;
    int rc = read_file(path, what, &data, &size, msg);
    if (rc != TC_OK) return rc;
    if (size < 16 || memcmp(data, MAGIC, 8) != 0) {
        free(data);
        return tc_fail(msg, TC_ERROR, "%s %s is not an array file (it does not start with %s)", what, path, MAGIC);
    }
    const uint32_t version = (uint32_t)le(data + 8, 4), count = (uint32_t)le(data + 12, 4);
    if (version != VERSION) {
        free(data);
        return tc_fail(msg, TC_ERROR, "%s %s is an array file of format version %u; this code reads version %u", what,
                       path, (unsigned)version, VERSION);
    }
    tc_arrays *a = calloc(1, sizeof *a);
    if (a != NULL && count > 0 && count <= size / 12) a->entries = calloc(count, sizeof *a->entries);
    if (a == NULL || (count > 0 && a->entries == NULL)) {
        free(data);
        tc_arrays_free(a);
        if (count > size / 12) return tc_fail(msg, TC_ERROR, "%s %s is malformed: %u entries cannot fit", what, path,
                                              (unsigned)count);
        return tc_fail(msg, TC_NOMEM, "out of memory reading %s %s", what, path);
    }
    char detail[400] = "";
    rc = parse(data, size, a, count, detail, sizeof detail);
    free(data);
    if (rc != TC_OK) {
        tc_arrays_free(a);
        if (rc == TC_NOMEM) return tc_fail(msg, TC_NOMEM, "out of memory reading %s %s", what, path);
        return tc_fail(msg, TC_ERROR, "%s %s is malformed: %s", what, path, detail);
    }
    *out = a;
    return TC_OK;
}
