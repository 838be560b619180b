/* Zip central directory (with ZIP64) and .npy header parsing for the friction table file; see tc_npz.h.
 *
 * Integers in both formats are little-endian; they are assembled byte by byte (rd16/rd32/rd64), so the
 * code reads the same on any host. Offsets are compared with the remaining length, never added first, so
 * that no arithmetic on values from the file can overflow.
 */
#include "tc_npz.h"

#include <stdio.h>
#include <string.h>

static uint32_t rd16(const unsigned char *p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8; }
static uint32_t rd32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint64_t rd64(const unsigned char *p) { return (uint64_t)rd32(p) | (uint64_t)rd32(p + 4) << 32; }

/* Record sizes and signatures (APPNOTE 4.3.7, 4.3.12, 4.3.14-16) */
enum { LOCAL_SIZE = 30, CENTRAL_SIZE = 46, EOCD_SIZE = 22, EOCD64_SIZE = 56, LOCATOR64_SIZE = 20 };
static const unsigned char SIG_LOCAL[4] = {'P', 'K', 3, 4};
static const unsigned char SIG_CENTRAL[4] = {'P', 'K', 1, 2};
static const unsigned char SIG_EOCD[4] = {'P', 'K', 5, 6};
static const unsigned char SIG_EOCD64[4] = {'P', 'K', 6, 6};
static const unsigned char SIG_LOCATOR64[4] = {'P', 'K', 6, 7};

/* zipfile refuses entries that need a newer version than 6.3 to extract */
#define MAX_EXTRACT_VERSION 63

/* ---- zip ---------------------------------------------------------------------------------------------- */

int tc_zip_open(tc_zip *zip, const unsigned char *data, size_t size, tc_msg msg) {
    memset(zip, 0, sizeof *zip);
    zip->data = data;
    zip->size = size;
    /* np.load decides by the first bytes: a zip starts with a local header (or is an empty archive) */
    if (size < 4 || (memcmp(data, SIG_LOCAL, 4) != 0 && memcmp(data, SIG_EOCD, 4) != 0))
        return tc_fail(msg, TC_ERROR, "not a zip archive (an .npz file starts with PK\\003\\004)");
    if (size < EOCD_SIZE) return tc_fail(msg, TC_ERROR, "not a zip archive: no end of central directory record");

    /* End of central directory: at the very end when there is no archive comment; otherwise the last
     * signature within the 64 KiB comment window (zipfile._EndRecData) */
    size_t eocd;
    if (memcmp(data + size - EOCD_SIZE, SIG_EOCD, 4) == 0 && data[size - 2] == 0 && data[size - 1] == 0) {
        eocd = size - EOCD_SIZE;
    } else {
        size_t lo = size > (size_t)65536 + EOCD_SIZE ? size - 65536 - EOCD_SIZE : 0;
        size_t i = size - 4 + 1;
        int found = 0;
        while (i-- > lo)
            if (memcmp(data + i, SIG_EOCD, 4) == 0) {
                found = 1;
                break;
            }
        if (!found || size - i < EOCD_SIZE)
            return tc_fail(msg, TC_ERROR, "not a zip archive: no end of central directory record");
        eocd = i;
    }
    uint64_t cd_size = rd32(data + eocd + 12);
    uint64_t cd_offset = rd32(data + eocd + 16);
    size_t location = eocd; /* where the (ZIP64) end record starts: the central directory ends there */

    /* ZIP64: a locator right before the end record, and the ZIP64 end record right before the locator */
    if (eocd >= LOCATOR64_SIZE && memcmp(data + eocd - LOCATOR64_SIZE, SIG_LOCATOR64, 4) == 0) {
        const unsigned char *loc = data + eocd - LOCATOR64_SIZE;
        if (rd32(loc + 4) != 0 || rd32(loc + 16) > 1)
            return tc_fail(msg, TC_ERROR, "zip archives that span multiple disks are not supported");
        if (eocd >= LOCATOR64_SIZE + EOCD64_SIZE &&
            memcmp(data + eocd - LOCATOR64_SIZE - EOCD64_SIZE, SIG_EOCD64, 4) == 0) {
            const unsigned char *rec = data + eocd - LOCATOR64_SIZE - EOCD64_SIZE;
            cd_size = rd64(rec + 40);
            cd_offset = rd64(rec + 48);
            location = eocd - LOCATOR64_SIZE - EOCD64_SIZE;
        }
    }
    if (cd_size > location) return tc_fail(msg, TC_ERROR, "bad offset for central directory");
    zip->cd_begin = location - (size_t)cd_size;
    zip->cd_size = (size_t)cd_size;
    zip->cd_offset = cd_offset;

    /* zipfile reads every entry when it opens an archive: a corrupt entry fails the whole file */
    size_t pos = 0;
    while (pos < zip->cd_size) {
        const unsigned char *e = data + zip->cd_begin + pos;
        size_t left = zip->cd_size - pos;
        if (left < CENTRAL_SIZE) return tc_fail(msg, TC_ERROR, "truncated central directory");
        if (memcmp(e, SIG_CENTRAL, 4) != 0) return tc_fail(msg, TC_ERROR, "bad magic number for central directory");
        if (e[6] > MAX_EXTRACT_VERSION)
            return tc_fail(msg, TC_ERROR, "zip file version %u.%u is not supported", e[6] / 10u, e[6] % 10u);
        /* the extra field is checked by tc_zip_find's decoder: run it here for every entry */
        size_t n = rd16(e + 28), m = rd16(e + 30), k = rd16(e + 32);
        size_t avail = left - CENTRAL_SIZE;
        size_t n_avail = n < avail ? n : avail;
        size_t m_avail = m < avail - n_avail ? m : avail - n_avail;
        const unsigned char *x = e + CENTRAL_SIZE + n_avail;
        while (m_avail >= 4) {
            size_t len = rd16(x + 2);
            if (len + 4 > m_avail)
                return tc_fail(msg, TC_ERROR, "corrupt extra field %04x (size=%u)", (unsigned)rd16(x), (unsigned)len);
            x += len + 4;
            m_avail -= len + 4;
        }
        pos += CENTRAL_SIZE + n + m + k;
    }
    return TC_OK;
}

/* One central directory entry, with the ZIP64 extra field applied (ZipInfo._decodeExtra). */
typedef struct cd_entry {
    const unsigned char *name;
    size_t name_len;
    unsigned flags, method;
    uint32_t crc;
    uint64_t compressed, uncompressed, header_offset;
} cd_entry;

static int read_entry(const tc_zip *zip, size_t pos, cd_entry *out, size_t *next, tc_msg msg) {
    const unsigned char *e = zip->data + zip->cd_begin + pos;
    size_t avail = zip->cd_size - pos - CENTRAL_SIZE; /* tc_zip_open checked that 46 bytes fit */
    size_t n = rd16(e + 28), m = rd16(e + 30), k = rd16(e + 32);
    /* like zipfile, which reads the directory into a buffer: fields past its end come out short */
    size_t n_avail = n < avail ? n : avail;
    size_t m_avail = m < avail - n_avail ? m : avail - n_avail;
    out->name = e + CENTRAL_SIZE;
    out->name_len = n_avail;
    out->flags = rd16(e + 8);
    out->method = rd16(e + 10);
    out->crc = rd32(e + 16);
    out->compressed = rd32(e + 20);
    out->uncompressed = rd32(e + 24);
    out->header_offset = rd32(e + 42);
    const unsigned char *x = e + CENTRAL_SIZE + n_avail;
    while (m_avail >= 4) {
        size_t type = rd16(x), len = rd16(x + 2);
        if (len + 4 > m_avail)
            return tc_fail(msg, TC_ERROR, "corrupt extra field %04x (size=%u)", (unsigned)type, (unsigned)len);
        if (type == 0x0001) {
            /* ZIP64 extended information (APPNOTE 4.5.3): only the fields saturated at 0xFFFFFFFF, in order */
            const unsigned char *d = x + 4;
            size_t d_len = len;
            if (out->uncompressed == 0xFFFFFFFFu || out->uncompressed == UINT64_MAX) {
                if (d_len < 8) return tc_fail(msg, TC_ERROR, "corrupt zip64 extra field: file size not found");
                out->uncompressed = rd64(d);
                d += 8;
                d_len -= 8;
            }
            if (out->compressed == 0xFFFFFFFFu) {
                if (d_len < 8) return tc_fail(msg, TC_ERROR, "corrupt zip64 extra field: compress size not found");
                out->compressed = rd64(d);
                d += 8;
                d_len -= 8;
            }
            if (out->header_offset == 0xFFFFFFFFu) {
                if (d_len < 8) return tc_fail(msg, TC_ERROR, "corrupt zip64 extra field: header offset not found");
                out->header_offset = rd64(d);
            }
        }
        x += len + 4;
        m_avail -= len + 4;
    }
    *next = pos + CENTRAL_SIZE + n + m + k;
    return TC_OK;
}

static const char *method_name(unsigned method) {
    switch (method) {
    case 8: return "deflate";
    case 9: return "deflate64";
    case 12: return "bzip2";
    case 14: return "lzma";
    case 93: return "zstandard";
    default: return "an unknown method";
    }
}

/* CRC-32 (ISO 3309, reflected polynomial 0xEDB88320) as zip and zlib compute it. The 1 KiB table is
 * built per call, on the stack: cheap next to the bytes it checks, and no global state. */
static uint32_t crc32_of(const unsigned char *p, size_t n) {
    uint32_t table[256];
    for (uint32_t i = 0; i < 256; ++i) {
        uint32_t c = i;
        for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
        table[i] = c;
    }
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFFu] ^ (crc >> 8);
    return crc ^ 0xFFFFFFFFu;
}

int tc_zip_find(const tc_zip *zip, const char *name, tc_zip_member *member, tc_msg msg) {
    size_t want = strlen(name);
    cd_entry e = {0}, entry;
    int found = 0;
    size_t pos = 0, next;
    while (pos < zip->cd_size) {
        int rc = read_entry(zip, pos, &entry, &next, msg);
        if (rc != TC_OK) return rc;
        if (entry.name_len == want && memcmp(entry.name, name, want) == 0) {
            e = entry; /* the last entry of a repeated name wins, as in zipfile's NameToInfo */
            found = 1;
        }
        pos = next;
    }
    if (!found) return tc_fail(msg, TC_ERROR, "there is no item named '%s' in the archive", name);

    /* The local header sits at header_offset from the archive's origin, which is cd_begin - cd_offset
     * (zipfile's "concat" of bytes prepended to the archive). Computed without leaving [0, size]. */
    size_t size = zip->size, local;
    if (e.header_offset >= zip->cd_offset) {
        uint64_t ahead = e.header_offset - zip->cd_offset;
        if (ahead > size - zip->cd_begin) return tc_fail(msg, TC_ERROR, "truncated file header of '%s'", name);
        local = zip->cd_begin + (size_t)ahead;
    } else {
        uint64_t behind = zip->cd_offset - e.header_offset;
        if (behind > zip->cd_begin) return tc_fail(msg, TC_ERROR, "bad offset for the file header of '%s'", name);
        local = zip->cd_begin - (size_t)behind;
    }
    if (size - local < LOCAL_SIZE) return tc_fail(msg, TC_ERROR, "truncated file header of '%s'", name);
    const unsigned char *h = zip->data + local;
    if (memcmp(h, SIG_LOCAL, 4) != 0)
        return tc_fail(msg, TC_ERROR, "bad magic number for the file header of '%s'", name);
    size_t n = rd16(h + 26), m = rd16(h + 28);
    size_t after = size - local - LOCAL_SIZE;
    if (e.flags & 0x20u) return tc_fail(msg, TC_ERROR, "'%s' holds compressed patched data (flag bit 5)", name);
    if (e.flags & 0x40u) return tc_fail(msg, TC_ERROR, "'%s' uses strong encryption (flag bit 6)", name);
    if (n != want || n > after || memcmp(h + LOCAL_SIZE, name, want) != 0)
        return tc_fail(msg, TC_ERROR, "file name in directory '%s' and in its local header differ", name);
    if (e.flags & 0x01u) return tc_fail(msg, TC_ERROR, "'%s' is encrypted", name);
    if (e.method != 0)
        return tc_fail(msg, TC_ERROR,
                       "'%s' is compressed (%s, zip method %u); the native reader reads uncompressed tables as "
                       "write_table writes them (np.savez, not np.savez_compressed)",
                       name, method_name(e.method), e.method);
    /* zipfile reads a stored member until either size runs out, and checks the CRC of what it read */
    uint64_t stored = e.compressed < e.uncompressed ? e.compressed : e.uncompressed;
    if (m > after - n || stored > after - n - m)
        return tc_fail(msg, TC_ERROR, "'%s' is truncated (%llu bytes declared)", name, (unsigned long long)stored);
    member->offset = local + LOCAL_SIZE + n + m;
    member->size = (size_t)stored;
    if (crc32_of(zip->data + member->offset, member->size) != e.crc)
        return tc_fail(msg, TC_ERROR, "bad CRC-32 for file '%s'", name);
    return TC_OK;
}

int tc_zip_has(const tc_zip *zip, const char *name) {
    size_t want = strlen(name), pos = 0, next;
    cd_entry entry;
    tc_msg quiet = {NULL, 0};
    while (pos < zip->cd_size) {
        if (read_entry(zip, pos, &entry, &next, quiet) != TC_OK) return 0; /* tc_zip_open checked every entry */
        if (entry.name_len == want && memcmp(entry.name, name, want) == 0) return 1;
        pos = next;
    }
    return 0;
}

/* ---- npy ---------------------------------------------------------------------------------------------- */

/* numpy.lib.format refuses headers longer than this (max_header_size) */
#define NPY_MAX_HEADER 10000

typedef struct hdr {
    const unsigned char *s;
    size_t i, n;
} hdr;

/* Python's whitespace inside brackets (not \v, which its tokenizer refuses) */
static void hdr_ws(hdr *h) {
    while (h->i < h->n && (h->s[h->i] == ' ' || h->s[h->i] == '\t' || h->s[h->i] == '\n' || h->s[h->i] == '\r' ||
                           h->s[h->i] == '\f'))
        ++h->i;
}

static int hdr_char(hdr *h, unsigned char c) {
    hdr_ws(h);
    if (h->i < h->n && h->s[h->i] == c) {
        ++h->i;
        return 1;
    }
    return 0;
}

/* A Python string literal in single or double quotes, without escapes (numpy writes none). */
static int hdr_string(hdr *h, const unsigned char **str, size_t *len) {
    hdr_ws(h);
    if (h->i >= h->n || (h->s[h->i] != '\'' && h->s[h->i] != '"')) return 0;
    unsigned char q = h->s[h->i++];
    size_t b = h->i;
    while (h->i < h->n && h->s[h->i] != q) {
        if (h->s[h->i] == '\\' || h->s[h->i] == '\n' || h->s[h->i] < 0x20 || h->s[h->i] > 0x7E) return 0;
        ++h->i;
    }
    if (h->i >= h->n) return 0;
    *str = h->s + b;
    *len = h->i - b;
    ++h->i;
    return 1;
}

static int hdr_word(hdr *h, const char *w) {
    size_t len = strlen(w);
    hdr_ws(h);
    if (h->n - h->i < len || memcmp(h->s + h->i, w, len) != 0) return 0;
    /* a whole word: True, not Truex */
    if (h->i + len < h->n) {
        unsigned char c = h->s[h->i + len];
        if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_') return 0;
    }
    h->i += len;
    return 1;
}

/* A non-negative decimal Python int (no sign, no underscores); 0 if absent or not an int, -1 if too large. */
static int hdr_uint(hdr *h, uint64_t *v) {
    hdr_ws(h);
    size_t b = h->i;
    uint64_t x = 0;
    while (h->i < h->n && h->s[h->i] >= '0' && h->s[h->i] <= '9') {
        unsigned d = (unsigned)(h->s[h->i] - '0');
        if (x > (UINT64_MAX - d) / 10) return -1;
        x = x * 10 + d;
        ++h->i;
    }
    if (h->i == b) return 0;
    if (h->s[b] == '0' && x != 0) return 0; /* Python reads 00 as 0 but refuses 01 */
    *v = x;
    return 1;
}

static int parse_shape(hdr *h, tc_npy *npy) {
    if (!hdr_char(h, '(')) return 0;
    npy->ndim = 0;
    if (hdr_char(h, ')')) return 1;
    for (;;) {
        uint64_t d;
        int rc = hdr_uint(h, &d);
        if (rc <= 0 || npy->ndim >= TC_NPY_MAX_DIMS) return 0;
        npy->shape[npy->ndim++] = d;
        if (hdr_char(h, ')')) return npy->ndim > 1; /* (6) is an int in parentheses, not a tuple */
        if (!hdr_char(h, ',')) return 0;
        if (hdr_char(h, ')')) return 1;
    }
}

int tc_npy_parse(const unsigned char *p, size_t n, const char *name, tc_npy *npy, tc_msg msg) {
    static const unsigned char MAGIC[6] = {0x93, 'N', 'U', 'M', 'P', 'Y'};
    memset(npy, 0, sizeof *npy);
    if (n < 8 || memcmp(p, MAGIC, 6) != 0)
        return tc_fail(msg, TC_ERROR, "'%s' is not a .npy array (no \\x93NUMPY magic)", name);
    size_t start, len;
    if (p[6] == 1 && p[7] == 0) {
        if (n < 10) return tc_fail(msg, TC_ERROR, "'%s' is truncated in its header", name);
        len = rd16(p + 8);
        start = 10;
    } else if ((p[6] == 2 || p[6] == 3) && p[7] == 0) {
        if (n < 12) return tc_fail(msg, TC_ERROR, "'%s' is truncated in its header", name);
        uint32_t len32 = rd32(p + 8);
        if (len32 > NPY_MAX_HEADER)
            return tc_fail(msg, TC_ERROR, "'%s' has a header of %lu bytes; numpy reads at most %d", name,
                           (unsigned long)len32, NPY_MAX_HEADER);
        len = len32;
        start = 12;
    } else {
        return tc_fail(msg, TC_ERROR, "'%s' has .npy format version (%u, %u); versions (1, 0), (2, 0), (3, 0) are read",
                       name, (unsigned)p[6], (unsigned)p[7]);
    }
    if (len > NPY_MAX_HEADER)
        return tc_fail(msg, TC_ERROR, "'%s' has a header of %u bytes; numpy reads at most %d", name, (unsigned)len,
                       NPY_MAX_HEADER);
    if (len > n - start) return tc_fail(msg, TC_ERROR, "'%s' is truncated in its header", name);

    hdr h = {p + start, 0, len};
    int have_descr = 0, have_fortran = 0, have_shape = 0;
    if (!hdr_char(&h, '{')) return tc_fail(msg, TC_ERROR, "'%s' has a header that is not a dictionary", name);
    while (!hdr_char(&h, '}')) {
        const unsigned char *key;
        size_t key_len;
        if (!hdr_string(&h, &key, &key_len) || !hdr_char(&h, ':'))
            return tc_fail(msg, TC_ERROR, "'%s' has a header that cannot be parsed", name);
        if (key_len == 5 && memcmp(key, "descr", 5) == 0 && !have_descr) {
            const unsigned char *v;
            size_t v_len;
            if (!hdr_string(&h, &v, &v_len) || v_len >= sizeof npy->descr)
                return tc_fail(msg, TC_ERROR, "'%s' has a descr that is not a plain dtype string", name);
            memcpy(npy->descr, v, v_len);
            npy->descr[v_len] = '\0';
            have_descr = 1;
        } else if (key_len == 13 && memcmp(key, "fortran_order", 13) == 0 && !have_fortran) {
            if (hdr_word(&h, "True")) npy->fortran_order = 1;
            else if (hdr_word(&h, "False")) npy->fortran_order = 0;
            else return tc_fail(msg, TC_ERROR, "'%s' has a fortran_order that is not a valid bool", name);
            have_fortran = 1;
        } else if (key_len == 5 && memcmp(key, "shape", 5) == 0 && !have_shape) {
            if (!parse_shape(&h, npy))
                return tc_fail(msg, TC_ERROR, "'%s' has a shape that is not a tuple of at most %d non-negative ints",
                               name, TC_NPY_MAX_DIMS);
            have_shape = 1;
        } else {
            return tc_fail(msg, TC_ERROR, "'%s' has a header that does not contain the correct keys", name);
        }
        if (hdr_char(&h, '}')) break;
        if (!hdr_char(&h, ',')) return tc_fail(msg, TC_ERROR, "'%s' has a header that cannot be parsed", name);
    }
    hdr_ws(&h);
    if (h.i != h.n) return tc_fail(msg, TC_ERROR, "'%s' has text after its header dictionary", name);
    if (!have_descr || !have_fortran || !have_shape)
        return tc_fail(msg, TC_ERROR, "'%s' has a header that does not contain the correct keys", name);
    uint64_t count = 1;
    for (size_t i = 0; i < npy->ndim; ++i) {
        if (npy->shape[i] != 0 && count > UINT64_MAX / npy->shape[i])
            return tc_fail(msg, TC_ERROR, "'%s' has a shape too large to hold", name);
        count *= npy->shape[i];
    }
    npy->count = count;
    npy->data_offset = start + len;
    return TC_OK;
}

void tc_npy_shape_repr(const tc_npy *npy, char *buf, size_t size) {
    size_t used = 0;
    if (size == 0) return;
    buf[0] = '\0';
    for (size_t i = 0; i <= npy->ndim + 1; ++i) {
        char part[32];
        if (i == 0) snprintf(part, sizeof part, "(");
        else if (i <= npy->ndim) snprintf(part, sizeof part, "%s%llu%s", i > 1 ? ", " : "",
                                         (unsigned long long)npy->shape[i - 1], npy->ndim == 1 ? "," : "");
        else snprintf(part, sizeof part, ")");
        size_t len = strlen(part);
        if (used + len >= size) return; /* truncated: only messages use shapes this long */
        memcpy(buf + used, part, len + 1);
        used += len;
    }
}
