/* tc_table_read: the friction table file (.npz) that table.write_table writes, read and verified in C.
 *
 * The format's owner is tribocosim/components/stripdraw/table.py (write_table, read_table); this reader
 * mirrors read_table step by step, with its messages:
 *   1. the file must exist                         "friction table file not found: PATH"
 *   2. np.load: a zip archive (tc_npz) with the members pressure.npy, velocity.npy, beta.npy, mu.npy
 *      ('<f8', C order) and metadata.npy (a 0-d '<U' array: UTF-32LE code units of a JSON object)
 *                                                  "friction table PATH is malformed: ..."
 *   3. metadata "format" and "format_version"      "friction table PATH has format ... version ...;
 *                                                   this version reads ... version 1"
 *   4. FrictionTable.__post_init__: 1-D non-empty axes, mu of shape (nP, nv, nb), then the checks of
 *      tc_table_from_arrays (increasing finite axes, finite mu >= 0, beta_threshold in (0, 1])
 *                                                  "friction table PATH is malformed: table ..."
 *   5. the content hash, SHA-256 of "tribocosim-friction-table:1", then per array (pressure, velocity,
 *      beta, mu) its name, its shape as Python prints the tuple and its little-endian float64 bytes, then
 *      the metadata JSON without "content_hash" and with compact separators (tc_json_hashed_text derives
 *      that text from the stored one)    "friction table PATH fails its content hash check (modified or corrupt)"
 *
 * Beyond read_table, this reader refuses compressed members (np.savez_compressed), dtypes other than '<f8'
 * for the arrays and '<U' for the metadata, Fortran-ordered mu, and metadata JSON not in the form
 * json.dumps(sort_keys=True) writes: write_table never writes any of these.
 */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tc_json.h"
#include "tc_npz.h"
#include "tc_sha256.h"
#include "tc_table.h"

#define FORMAT_NAME "tribocosim-friction-table"
/* a sanity bound: the shipped table is 180 kB, a 200^3 table 64 MB */
#define MAX_FILE_SIZE ((size_t)1 << 30)

/* one float64 array of the file */
typedef struct numeric {
    const char *name;           /* pressure, velocity, beta, mu */
    tc_npy npy;
    const unsigned char *bytes; /* its data in the file buffer: count * 8 bytes, little-endian */
    size_t count;
    double *values;
} numeric;

static int read_file(const char *path, unsigned char **data, size_t *size, tc_msg msg) {
    errno = 0;
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
#if defined(ENOENT)
        if (errno != ENOENT && errno != 0)
            return tc_fail(msg, TC_ERROR, "friction table file cannot be opened: %s", path);
#endif
        return tc_fail(msg, TC_ERROR, "friction table file not found: %s", path);
    }
    size_t cap = (size_t)1 << 16, used = 0;
    unsigned char *buf = malloc(cap);
    int rc = TC_OK;
    if (buf == NULL) rc = tc_fail(msg, TC_NOMEM, "out of memory reading friction table %s", path);
    while (rc == TC_OK) {
        if (used == cap) { /* cap <= MAX_FILE_SIZE here, so doubling it cannot overflow */
            unsigned char *bigger = realloc(buf, cap * 2);
            if (bigger == NULL) {
                rc = tc_fail(msg, TC_NOMEM, "out of memory reading friction table %s", path);
                break;
            }
            buf = bigger;
            cap *= 2;
        }
        used += fread(buf + used, 1, cap - used, f);
        if (ferror(f)) /* a directory, for one: read_table's is_file() says "not found" */
            rc = tc_fail(msg, TC_ERROR, "friction table file not found: %s (it cannot be read as a file)", path);
        else if (used > MAX_FILE_SIZE)
            rc = tc_fail(msg, TC_ERROR, "friction table %s is larger than 1 GiB; the native reader refuses it", path);
        else if (feof(f)) break;
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

static int load_numeric(const tc_zip *zip, numeric *a, tc_msg msg) {
    char member[32], shape[128];
    tc_zip_member m;
    int rc;
    snprintf(member, sizeof member, "%s.npy", a->name);
    if ((rc = tc_zip_find(zip, member, &m, msg)) != TC_OK) return rc;
    if ((rc = tc_npy_parse(zip->data + m.offset, m.size, member, &a->npy, msg)) != TC_OK) return rc;
    if (strcmp(a->npy.descr, "<f8") != 0)
        return tc_fail(msg, TC_ERROR, "'%s' has dtype '%s'; the table needs '<f8' (little-endian float64)", member,
                       a->npy.descr);
    /* Fortran order changes nothing for one dimension; numpy writes False there anyway */
    if (a->npy.fortran_order && a->npy.ndim > 1)
        return tc_fail(msg, TC_ERROR, "'%s' is stored in Fortran order; the table needs C order", member);
    size_t avail = m.size - a->npy.data_offset; /* tc_npy_parse checked data_offset <= m.size */
    if (a->npy.count > avail / 8) {
        tc_npy_shape_repr(&a->npy, shape, sizeof shape);
        return tc_fail(msg, TC_ERROR, "'%s' is truncated: shape %s needs more than the %llu bytes of data it holds",
                       member, shape, (unsigned long long)avail);
    }
    a->count = (size_t)a->npy.count;
    a->bytes = zip->data + m.offset + a->npy.data_offset;
    a->values = malloc(a->count > 0 ? a->count * sizeof(double) : sizeof(double));
    if (a->values == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for '%s'", member);
    for (size_t i = 0; i < a->count; ++i) {
        /* little-endian bytes -> the host's float64 (IEEE 754 binary64, same byte order as uint64_t) */
        const unsigned char *p = a->bytes + 8 * i;
        uint64_t bits = 0;
        for (int k = 7; k >= 0; --k) bits = bits << 8 | p[k];
        memcpy(&a->values[i], &bits, sizeof bits);
    }
    return TC_OK;
}

/* The metadata text: the UTF-32LE code units narrowed to bytes (ASCII kept, any other character as the
 * stand-in byte 0x80, see tc_json.h), trailing NULs dropped as numpy drops them from '<U' items. */
static int load_metadata(const tc_zip *zip, char **text, size_t *text_n, tc_msg msg) {
    static const char member[] = "metadata.npy";
    tc_zip_member m;
    tc_npy npy;
    char shape[128];
    int rc;
    if ((rc = tc_zip_find(zip, member, &m, msg)) != TC_OK) return rc;
    if ((rc = tc_npy_parse(zip->data + m.offset, m.size, member, &npy, msg)) != TC_OK) return rc;
    uint64_t units = 0;
    int ok = npy.descr[0] == '<' && npy.descr[1] == 'U' && npy.descr[2] != '\0';
    for (const char *p = npy.descr + 2; ok && *p != '\0'; ++p) {
        if (*p < '0' || *p > '9' || units > (UINT64_MAX - 9) / 10) ok = 0;
        else units = units * 10 + (uint64_t)(*p - '0');
    }
    if (!ok) return tc_fail(msg, TC_ERROR, "'%s' has dtype '%s'; the metadata is a '<U' string", member, npy.descr);
    if (npy.ndim != 0) {
        tc_npy_shape_repr(&npy, shape, sizeof shape);
        return tc_fail(msg, TC_ERROR, "'%s' has shape %s; the metadata is a 0-d string array", member, shape);
    }
    size_t avail = m.size - npy.data_offset;
    if (units > avail / 4)
        return tc_fail(msg, TC_ERROR, "'%s' is truncated: its dtype needs more than the %llu bytes of data it holds",
                       member, (unsigned long long)avail);
    const unsigned char *p = zip->data + m.offset + npy.data_offset;
    size_t n = (size_t)units;
    while (n > 0 && (p[4 * (n - 1)] | p[4 * (n - 1) + 1] | p[4 * (n - 1) + 2] | p[4 * (n - 1) + 3]) == 0) --n;
    unsigned char *t = malloc(n > 0 ? n : 1);
    if (t == NULL) return tc_fail(msg, TC_NOMEM, "out of memory for '%s'", member);
    for (size_t i = 0; i < n; ++i) {
        const unsigned char *u = p + 4 * i;
        t[i] = (u[1] | u[2] | u[3]) == 0 && u[0] < 0x80 ? u[0] : 0x80;
    }
    *text = (char *)t;
    *text_n = n;
    return TC_OK;
}

static void hash_text(tc_sha256 *h, const char *s) { tc_sha256_update(h, s, strlen(s)); }

int tc_table_read(const char *path, tc_table **out, tc_msg msg) {
    if (out == NULL) return tc_fail(msg, TC_ERROR, "tc_table_read needs somewhere to put the table");
    *out = NULL;
    if (path == NULL) return tc_fail(msg, TC_ERROR, "no friction table path given");
    unsigned char *data = NULL;
    size_t size = 0;
    int rc = read_file(path, &data, &size, msg);
    if (rc != TC_OK) return rc;

    char detail[512], shape[128], want[128];
    tc_msg d = {detail, sizeof detail};
    detail[0] = '\0';
    numeric arrays[8] = {{.name = "pressure"},     {.name = "velocity"},      {.name = "beta"},
                         {.name = "mu"},           {.name = "contact_area"},  {.name = "particle_area"},
                         {.name = "contact_area_std"}, {.name = "particle_area_std"}};
    int version = 1, n_arrays = 4; /* version 2 adds the four areas */
    char *text = NULL, *hashed = NULL;
    size_t text_n = 0, hashed_n = 0;
    tc_table *table = NULL;
    tc_zip zip;

    /* 2. the members, in read_table's order, then the metadata as JSON */
    if ((rc = tc_zip_open(&zip, data, size, d)) != TC_OK) goto malformed;
    for (int k = 0; k < 4; ++k)
        if ((rc = load_numeric(&zip, &arrays[k], d)) != TC_OK) goto malformed;
    if ((rc = load_metadata(&zip, &text, &text_n, d)) != TC_OK) goto malformed;
    if ((rc = tc_json_check_object(text, text_n, d)) != TC_OK) goto malformed;

    /* 3. format and version; like Python's ==, 1.0 and true equal 1 */
    {
        tc_json_value format = tc_json_member(text, text_n, "format");
        tc_json_value vvalue = tc_json_member(text, text_n, "format_version");
        double v;
        if (!tc_json_string_equals(text, format, FORMAT_NAME) || !tc_json_number(text, vvalue, &v) ||
            (v != 1 && v != 2)) {
            char f[128], vr[80];
            tc_json_repr(text, format, f, sizeof f);
            tc_json_repr(text, vvalue, vr, sizeof vr);
            rc = tc_fail(msg, TC_ERROR,
                         "friction table %s has format %s version %s; this version reads '%s' versions 1 and 2", path,
                         f, vr, FORMAT_NAME);
            goto done;
        }
        version = (int)v;
        n_arrays = version == 2 ? 8 : 4;
        for (int k = 4; k < n_arrays; ++k)
            if ((rc = load_numeric(&zip, &arrays[k], d)) != TC_OK) goto malformed;
    }

    /* 4. shapes, then the value checks of FrictionTable.__post_init__ */
    for (int k = 0; k < 3; ++k)
        if (arrays[k].npy.ndim != 1 || arrays[k].count < 1) {
            tc_npy_shape_repr(&arrays[k].npy, shape, sizeof shape);
            rc = tc_fail(d, TC_ERROR, "table axis %s must be a non-empty 1-D array, got shape %s", arrays[k].name,
                         shape);
            goto malformed;
        }
    const numeric *mu = &arrays[3];
    for (int k = 3; k < n_arrays; ++k) {
        const numeric *a = &arrays[k];
        if (a->npy.ndim != 3 || a->npy.shape[0] != arrays[0].count || a->npy.shape[1] != arrays[1].count ||
            a->npy.shape[2] != arrays[2].count) {
            tc_npy_shape_repr(&a->npy, shape, sizeof shape);
            snprintf(want, sizeof want, "(%llu, %llu, %llu)", (unsigned long long)arrays[0].count,
                     (unsigned long long)arrays[1].count, (unsigned long long)arrays[2].count);
            rc = tc_fail(d, TC_ERROR, "table %s has shape %s; the axes need %s", a->name, shape, want);
            goto malformed;
        }
    }
    {
        tc_json_value bt_value = tc_json_member(text, text_n, "beta_threshold");
        double bt = 0;
        int bt_ok = tc_json_python_float(text, bt_value, &bt) && bt > 0 && bt <= 1; /* float(bt) in Python */
        /* the array checks come first in Python: run them with a valid threshold, then judge the threshold
         * with Python's message (its value as repr prints it) */
        rc = tc_table_from_arrays(arrays[0].count, arrays[1].count, arrays[2].count, arrays[0].values,
                                  arrays[1].values, arrays[2].values, mu->values, bt_ok ? bt : 1.0, &table, d);
        if (rc == TC_OK && version == 2)
            rc = tc_table_set_areas(table, arrays[4].values, arrays[5].values, arrays[6].values, arrays[7].values, d);
        if (rc != TC_OK) goto malformed;
        if (!bt_ok) {
            char r[80];
            tc_json_repr(text, bt_value, r, sizeof r);
            rc = tc_fail(d, TC_ERROR, "table metadata beta_threshold = %s; a value in (0, 1] is required", r);
            goto malformed;
        }
    }

    /* 5. the content hash */
    hashed = malloc(text_n > 0 ? text_n : 1);
    if (hashed == NULL) {
        rc = tc_fail(d, TC_NOMEM, "out of memory for the metadata");
        goto malformed;
    }
    if ((rc = tc_json_hashed_text(text, text_n, "content_hash", hashed, &hashed_n, d)) != TC_OK) {
        if (rc == TC_NOMEM) goto malformed;
        rc = tc_fail(msg, TC_ERROR, "friction table %s is malformed: its metadata JSON is not in the form write_table "
                     "writes (%s), so its content hash cannot be checked", path, detail);
        goto done;
    }
    {
        tc_sha256 h;
        unsigned char digest[32];
        char hex[65];
        char head[64];
        tc_sha256_init(&h);
        snprintf(head, sizeof head, "%s:%d", FORMAT_NAME, version);
        hash_text(&h, head);
        for (int k = 0; k < n_arrays; ++k) {
            hash_text(&h, arrays[k].name);
            tc_npy_shape_repr(&arrays[k].npy, shape, sizeof shape);
            hash_text(&h, shape);
            tc_sha256_update(&h, arrays[k].bytes, arrays[k].count * 8);
        }
        tc_sha256_update(&h, hashed, hashed_n);
        tc_sha256_final(&h, digest);
        tc_sha256_hex(digest, hex);
        if (!tc_json_string_equals(text, tc_json_member(text, text_n, "content_hash"), hex)) {
            rc = tc_fail(msg, TC_ERROR, "friction table %s fails its content hash check (modified or corrupt)", path);
            goto done;
        }
        memcpy(table->content_hash, hex, sizeof hex);
    }
    table->format_version = version;
    {
        /* str(metadata.get("provenance", "unknown")), cut to the struct's 31 bytes */
        tc_json_value p = tc_json_member(text, text_n, "provenance");
        if (p.kind == TC_JSON_ABSENT) snprintf(table->provenance, sizeof table->provenance, "unknown");
        else if (p.kind == TC_JSON_STRING) tc_json_string(text, p, table->provenance, sizeof table->provenance);
        else tc_json_repr(text, p, table->provenance, sizeof table->provenance);
    }
    *out = table;
    table = NULL;
    rc = TC_OK;
    goto done;

malformed:
    if (rc == TC_NOMEM) rc = tc_fail(msg, TC_NOMEM, "friction table %s cannot be read: %s", path, detail);
    else rc = tc_fail(msg, TC_ERROR, "friction table %s is malformed: %s", path, detail);
done:
    for (int k = 0; k < 8; ++k) free(arrays[k].values);
    free(text);
    free(hashed);
    free(data);
    tc_table_free(table);
    return rc;
}
