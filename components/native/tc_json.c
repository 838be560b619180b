/* Minimal JSON scanning of the friction table metadata; see tc_json.h for what is checked and why.
 *
 * One recursive-descent scanner serves every function: it validates the grammar of Python's json.loads
 * (RFC 8259 plus NaN/Infinity/-Infinity, strict strings), and on request checks the canonical form, writes
 * the hashed text, or notes where a top-level member's value is. Nothing is allocated except, rarely, a
 * buffer for a very long number token.
 */
#include "tc_json.h"

#include <locale.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct scanner {
    const char *s;
    size_t n, i;
    int canonical;         /* check the form json.dumps(sort_keys=True) writes */
    char *out;             /* the hashed text, when not NULL */
    size_t out_cap, out_n;
    const char *drop_key;  /* top-level member left out of out */
    const char *find_key;  /* top-level member whose value is noted in found */
    tc_json_value found;
    tc_msg msg;
} scanner;

static int is_digit(char c) { return c >= '0' && c <= '9'; }

static int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* the four hex digits of a \u escape that the scanner has validated */
static long hex4(const char *p) {
    long v = 0;
    for (int k = 0; k < 4; ++k) v = v * 16 + hex_value(p[k]);
    return v;
}

/* ---- decoding of validated strings ----------------------------------------------------------------- */

typedef struct cp_iter {
    const char *s;
    size_t i, end; /* the string's body: after the opening quote, up to the closing one */
} cp_iter;

static cp_iter string_body(const char *text, tc_json_value v) {
    cp_iter it = {text, v.begin + 1, v.end - 1};
    return it;
}

/* The next code point, or -1 at the end. A \u high surrogate followed by a \u low surrogate is one code
 * point, as json.loads joins them; a lone surrogate stays a code point of its own (Python strings keep it).
 * A byte >= 0x80 (the stand-in for non-ASCII text) comes out as itself. */
static long cp_next(cp_iter *it) {
    if (it->i >= it->end) return -1;
    unsigned char c = (unsigned char)it->s[it->i];
    if (c != '\\') {
        ++it->i;
        return c;
    }
    char e = it->s[it->i + 1];
    it->i += 2;
    switch (e) {
    case 'b': return 0x08;
    case 'f': return 0x0c;
    case 'n': return 0x0a;
    case 'r': return 0x0d;
    case 't': return 0x09;
    case 'u': {
        long u = hex4(it->s + it->i);
        it->i += 4;
        if (u >= 0xd800 && u <= 0xdbff && it->end - it->i >= 6 && it->s[it->i] == '\\' && it->s[it->i + 1] == 'u') {
            long lo = hex4(it->s + it->i + 2);
            if (lo >= 0xdc00 && lo <= 0xdfff) {
                it->i += 6;
                return 0x10000 + ((u - 0xd800) << 10) + (lo - 0xdc00);
            }
        }
        return u;
    }
    default: return (unsigned char)e; /* \" \\ \/ */
    }
}

/* -1, 0, 1 as the decoded key a sorts before, equal to, after b (code point order, as Python sorts str) */
static int key_compare(const char *text, tc_json_value a, tc_json_value b) {
    cp_iter x = string_body(text, a), y = string_body(text, b);
    for (;;) {
        long p = cp_next(&x), q = cp_next(&y);
        if (p != q) return p < q ? -1 : 1;
        if (p < 0) return 0;
    }
}

int tc_json_string_equals(const char *text, tc_json_value v, const char *s) {
    if (v.kind != TC_JSON_STRING) return 0;
    cp_iter it = string_body(text, v);
    for (;; ++s) {
        long c = cp_next(&it);
        if (c < 0) return *s == '\0';
        if (*s == '\0' || c != (unsigned char)*s) return 0;
    }
}

int tc_json_string(const char *text, tc_json_value v, char *buf, size_t size) {
    if (v.kind != TC_JSON_STRING || size == 0) return TC_ERROR;
    cp_iter it = string_body(text, v);
    size_t used = 0;
    long c;
    while ((c = cp_next(&it)) >= 0) {
        unsigned char u[4];
        size_t len;
        if (c < 0x80) { u[0] = (unsigned char)c; len = 1; }
        else if (c < 0x800) {
            u[0] = (unsigned char)(0xc0 | c >> 6);
            u[1] = (unsigned char)(0x80 | (c & 0x3f));
            len = 2;
        }
        else if (c < 0x10000) {
            u[0] = (unsigned char)(0xe0 | c >> 12);
            u[1] = (unsigned char)(0x80 | (c >> 6 & 0x3f));
            u[2] = (unsigned char)(0x80 | (c & 0x3f));
            len = 3;
        } else {
            u[0] = (unsigned char)(0xf0 | c >> 18);
            u[1] = (unsigned char)(0x80 | (c >> 12 & 0x3f));
            u[2] = (unsigned char)(0x80 | (c >> 6 & 0x3f));
            u[3] = (unsigned char)(0x80 | (c & 0x3f));
            len = 4;
        }
        if (len >= size - used) break; /* keep room for the NUL; never split a character */
        memcpy(buf + used, u, len);
        used += len;
    }
    buf[used] = '\0';
    return TC_OK;
}

/* ---- numbers ------------------------------------------------------------------------------------------- */

/* the powers of ten that a double holds exactly */
static const double POW10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                                 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* strtod of a string written with '.', whatever the C locale's decimal point is (a host application may
 * have called setlocale). Returns -1 only if a buffer for a very long token cannot be allocated. */
static int strtod_dot(const char *s, size_t n, double *x) {
    const struct lconv *lc = localeconv();
    const char *dp = ".";
    if (lc != NULL && lc->decimal_point != NULL && lc->decimal_point[0] != '\0') dp = lc->decimal_point;
    size_t dp_len = strlen(dp);
    char small[128];
    size_t need = n * dp_len + 1;
    char *buf = need <= sizeof small ? small : malloc(need);
    if (buf == NULL) return -1;
    size_t used = 0;
    for (size_t i = 0; i < n; ++i) {
        if (s[i] == '.') {
            memcpy(buf + used, dp, dp_len);
            used += dp_len;
        } else {
            buf[used++] = s[i];
        }
    }
    buf[used] = '\0';
    *x = strtod(buf, NULL);
    if (buf != small) free(buf);
    return 0;
}

/* The double nearest to a JSON number token (validated). Clinger's fast path first: a mantissa below 2^53
 * times or over an exact power of ten up to 1e22 is one correctly rounded operation, independent of the C
 * library; the rest (long mantissas, large exponents) go to strtod. */
static int parse_double(const char *s, size_t n, double *x) {
    size_t i = 0;
    int neg = 0, exact = 1, digits = 0;
    uint64_t m = 0;
    long e10 = 0;
    if (i < n && s[i] == '-') {
        neg = 1;
        ++i;
    }
    for (; i < n && (is_digit(s[i]) || s[i] == '.'); ++i) {
        if (s[i] == '.') {
            for (++i; i < n && is_digit(s[i]); ++i) {
                if (m == 0 && s[i] == '0') { --e10; continue; }
                if (digits < 19) { m = m * 10 + (uint64_t)(s[i] - '0'); ++digits; --e10; }
                else if (s[i] != '0') exact = 0;
            }
            break;
        }
        if (m == 0 && s[i] == '0') continue;
        if (digits < 19) { m = m * 10 + (uint64_t)(s[i] - '0'); ++digits; }
        else { ++e10; if (s[i] != '0') exact = 0; }
    }
    if (i < n && (s[i] == 'e' || s[i] == 'E')) {
        long sign = 1, ex = 0;
        ++i;
        if (i < n && (s[i] == '+' || s[i] == '-')) sign = s[i++] == '-' ? -1 : 1;
        for (; i < n && is_digit(s[i]); ++i)
            if (ex < 100000) ex = ex * 10 + (s[i] - '0'); /* beyond that the value is 0 or inf anyway */
        e10 += sign * ex;
    }
    if (m == 0) {
        *x = neg ? -0.0 : 0.0;
        return 0;
    }
    if (exact && m <= ((uint64_t)1 << 53) && e10 >= -22 && e10 <= 22) {
        double d = (double)m;
        d = e10 >= 0 ? d * POW10[e10] : d / POW10[-e10];
        *x = neg ? -d : d;
        return 0;
    }
    return strtod_dot(s, n, x);
}

/* The significant digits and exponent of a "%.*e" text: digits into d (at most cap), *decpt with
 * value = 0.d * 10^decpt. The decimal point may be the locale's; only digits and 'e' are looked at. */
static int split_e(const char *buf, char *d, size_t cap, size_t *k, long *decpt) {
    const char *p = buf;
    *k = 0;
    for (; *p != '\0' && *p != 'e' && *p != 'E'; ++p)
        if (is_digit(*p)) {
            if (*k >= cap) return 0;
            d[(*k)++] = *p;
        }
    if (*p == '\0') return 0;
    ++p;
    long sign = 1, e = 0;
    if (*p == '+' || *p == '-') sign = *p++ == '-' ? -1 : 1;
    for (; is_digit(*p); ++p) e = e * 10 + (*p - '0');
    *decpt = sign * e + 1;
    return 1;
}

/* repr(float) layout (CPython's format_float_short, mode 'r'): exponent form when decpt <= -4 or > 16,
 * "1e+16", "1.5e-05"; otherwise positional with ".0" when integral. */
static void repr_layout(char *out, size_t size, int neg, const char *d, size_t k, long decpt) {
    size_t used = 0;
#define PUT(c) do { if (used + 1 < size) out[used++] = (c); } while (0)
    if (neg) PUT('-');
    if (decpt <= -4 || decpt > 16) {
        PUT(d[0]);
        if (k > 1) {
            PUT('.');
            for (size_t j = 1; j < k; ++j) PUT(d[j]);
        }
        char e[32];
        long x = decpt - 1;
        snprintf(e, sizeof e, "e%c%02ld", x < 0 ? '-' : '+', x < 0 ? -x : x);
        for (const char *p = e; *p; ++p) PUT(*p);
    } else if (decpt <= 0) {
        PUT('0');
        PUT('.');
        for (long j = 0; j < -decpt; ++j) PUT('0');
        for (size_t j = 0; j < k; ++j) PUT(d[j]);
    } else if ((size_t)decpt >= k) {
        for (size_t j = 0; j < k; ++j) PUT(d[j]);
        for (size_t j = k; j < (size_t)decpt; ++j) PUT('0');
        PUT('.');
        PUT('0');
    } else {
        for (size_t j = 0; j < k; ++j) {
            if (j == (size_t)decpt) PUT('.');
            PUT(d[j]);
        }
    }
#undef PUT
    out[used] = '\0';
}

/* 1 if the float token tok (value x) is exactly what repr(x) prints: the fewest digits that read back
 * as x, the nearest such, laid out as repr lays them out. The digit checks use printf/strtod of the C
 * library (correctly rounded in glibc, macOS and the UCRT); a mismatch only ever makes the reader refuse. */
static int float_token_is_repr(const char *tok, size_t n, double x) {
    if (!isfinite(x)) return 0; /* an overflowing literal reads as inf, which json.dumps writes Infinity */
    int neg = tok[0] == '-';
    char d[40];
    size_t k = 0, i = (size_t)neg;
    long decpt = 0;
    int in_frac = 0;
    for (; i < n && tok[i] != 'e' && tok[i] != 'E'; ++i) {
        if (tok[i] == '.') { in_frac = 1; continue; }
        if (k == 0 && tok[i] == '0') {
            if (in_frac) --decpt; /* a leading zero after the point moves the value down a decade */
            continue;
        }
        if (k >= sizeof d) return 0; /* more digits than any repr has */
        d[k++] = tok[i];
        if (!in_frac) ++decpt;
    }
    if (i < n) {
        long sign = 1, e = 0;
        ++i;
        if (tok[i] == '+' || tok[i] == '-') sign = tok[i++] == '-' ? -1 : 1;
        for (; i < n; ++i)
            if (e < 100000) e = e * 10 + (tok[i] - '0');
        decpt += sign * e;
    }
    if (x == 0) return (n == 3 && memcmp(tok, "0.0", 3) == 0) || (n == 4 && memcmp(tok, "-0.0", 4) == 0);
    while (k > 0 && d[k - 1] == '0') --k;
    if (k == 0 || k > 17) return 0;

    char buf[64], e_digits[40];
    size_t e_k;
    long e_decpt;
    double ax = fabs(x);
    snprintf(buf, sizeof buf, "%.*e", (int)k - 1, ax);
    if (!split_e(buf, e_digits, sizeof e_digits, &e_k, &e_decpt)) return 0;
    if (e_k != k || memcmp(e_digits, d, k) != 0 || e_decpt != decpt) return 0; /* not the nearest k digits */
    if (k > 1) {
        snprintf(buf, sizeof buf, "%.*e", (int)k - 2, ax);
        double y;
        if (strtod_dot(buf, strlen(buf), &y) != 0) return 0;
        /* buf carries the locale's decimal point; strtod_dot only rewrites '.', so it reads it back as is */
        if (y == ax) return 0; /* fewer digits would do */
    }
    char want[64];
    repr_layout(want, sizeof want, neg, d, k, decpt);
    return strlen(want) == n && memcmp(want, tok, n) == 0;
}

int tc_json_number(const char *text, tc_json_value v, double *x) {
    if (v.kind == TC_JSON_TRUE || v.kind == TC_JSON_FALSE) {
        *x = v.kind == TC_JSON_TRUE ? 1.0 : 0.0;
        return 1;
    }
    if (v.kind != TC_JSON_NUMBER) return 0;
    const char *t = text + v.begin;
    size_t n = v.end - v.begin;
    if (n == 3 && memcmp(t, "NaN", 3) == 0) *x = NAN;
    else if (n == 8 && memcmp(t, "Infinity", 8) == 0) *x = INFINITY;
    else if (n == 9 && memcmp(t, "-Infinity", 9) == 0) *x = -INFINITY;
    else if (parse_double(t, n, x) != 0) return 0;
    return 1;
}

static int ascii_lower_equals(const char *s, size_t n, const char *word) {
    if (strlen(word) != n) return 0;
    for (size_t i = 0; i < n; ++i)
        if ((s[i] >= 'A' && s[i] <= 'Z' ? s[i] - 'A' + 'a' : s[i]) != word[i]) return 0;
    return 1;
}

int tc_json_python_float(const char *text, tc_json_value v, double *x) {
    if (v.kind != TC_JSON_STRING) return tc_json_number(text, v, x);
    char buf[80];
    size_t n = 0, b = 0;
    cp_iter it = string_body(text, v);
    long c;
    while ((c = cp_next(&it)) >= 0) {
        if (c == 0 || c > 0x7f || n + 1 >= sizeof buf) return 0; /* non-ASCII digits and spaces: not handled */
        buf[n++] = (char)c;
    }
    buf[n] = '\0';
    /* float() strips whitespace (the ASCII kinds here) and takes an optional sign */
    while (b < n && strchr(" \t\n\r\v\f\x1c\x1d\x1e\x1f", buf[b]) != NULL) ++b;
    while (n > b && strchr(" \t\n\r\v\f\x1c\x1d\x1e\x1f", buf[n - 1]) != NULL) --n;
    int neg = 0;
    if (b < n && (buf[b] == '+' || buf[b] == '-')) neg = buf[b++] == '-';
    const char *s = buf + b;
    size_t len = n - b;
    if (ascii_lower_equals(s, len, "inf") || ascii_lower_equals(s, len, "infinity")) {
        *x = neg ? -INFINITY : INFINITY;
        return 1;
    }
    if (ascii_lower_equals(s, len, "nan")) {
        *x = NAN;
        return 1;
    }
    /* digits [. digits] or . digits, then [e [sign] digits] */
    size_t i = 0, mantissa_digits = 0;
    while (i < len && is_digit(s[i])) ++i, ++mantissa_digits;
    if (i < len && s[i] == '.')
        for (++i; i < len && is_digit(s[i]); ++i) ++mantissa_digits;
    if (mantissa_digits == 0) return 0;
    if (i < len && (s[i] == 'e' || s[i] == 'E')) {
        size_t j = i + 1;
        if (j < len && (s[j] == '+' || s[j] == '-')) ++j;
        if (j >= len || !is_digit(s[j])) return 0;
        while (j < len && is_digit(s[j])) ++j;
        i = j;
    }
    if (i != len) return 0;
    if (parse_double(s, len, x) != 0) return 0;
    if (neg) *x = -*x;
    return 1;
}

void tc_json_repr(const char *text, tc_json_value v, char *buf, size_t size) {
    const char *t = text + v.begin;
    size_t n = v.end - v.begin;
    if (size == 0) return;
    switch (v.kind) {
    case TC_JSON_ABSENT:
    case TC_JSON_NULL: snprintf(buf, size, "None"); return;
    case TC_JSON_TRUE: snprintf(buf, size, "True"); return;
    case TC_JSON_FALSE: snprintf(buf, size, "False"); return;
    case TC_JSON_STRING: {
        char decoded[96];
        tc_json_string(text, v, decoded, sizeof decoded);
        char q = strchr(decoded, '\'') != NULL && strchr(decoded, '"') == NULL ? '"' : '\'';
        snprintf(buf, size, "%c%s%c%s", q, decoded, q, strlen(decoded) >= sizeof decoded - 4 ? "..." : "");
        return;
    }
    case TC_JSON_NUMBER:
        if (n == 3 && memcmp(t, "NaN", 3) == 0) { snprintf(buf, size, "nan"); return; }
        if (n == 8 && memcmp(t, "Infinity", 8) == 0) { snprintf(buf, size, "inf"); return; }
        if (n == 9 && memcmp(t, "-Infinity", 9) == 0) { snprintf(buf, size, "-inf"); return; }
        break;
    default: break;
    }
    /* numbers as written; arrays and objects as their text, cut */
    if (n < 64) snprintf(buf, size, "%.*s", (int)n, t);
    else snprintf(buf, size, "%.60s...", t);
}

/* ---- the scanner --------------------------------------------------------------------------------------- */

static void emit(scanner *sc, const char *p, size_t len) {
    /* the output is a subsequence of the input, so it always fits; the check is for safety only */
    if (sc->out == NULL || len > sc->out_cap - sc->out_n) return;
    memcpy(sc->out + sc->out_n, p, len);
    sc->out_n += len;
}

static int syntax(scanner *sc, const char *what) {
    return tc_fail(sc->msg, TC_ERROR, "metadata is not valid JSON: %s at character %llu", what,
                   (unsigned long long)sc->i);
}

static int departure(scanner *sc, size_t at, const char *what) {
    return tc_fail(sc->msg, TC_ERROR, "%s at character %llu", what, (unsigned long long)at);
}

static void skip_ws(scanner *sc) {
    for (; sc->i < sc->n; ++sc->i) {
        char c = sc->s[sc->i];
        if (c != ' ' && c != '\t' && c != '\n' && c != '\r') break;
    }
}

static int parse_value(scanner *sc, int depth, tc_json_value *v);

static int parse_string(scanner *sc, tc_json_value *v) {
    const char *s = sc->s;
    size_t b = sc->i++;
    for (;;) {
        if (sc->i >= sc->n) return syntax(sc, "unterminated string");
        unsigned char c = (unsigned char)s[sc->i];
        if (c == '"') break;
        if (c < 0x20) return syntax(sc, "invalid control character in a string");
        if (c != '\\') {
            if (sc->canonical && c >= 0x7f)
                return departure(sc, sc->i, c == 0x7f ? "unescaped DEL character" : "non-ASCII character");
            ++sc->i;
            continue;
        }
        if (sc->n - sc->i < 2) return syntax(sc, "unterminated string");
        char e = s[sc->i + 1];
        if (e == 'u') {
            if (sc->n - sc->i < 6) return syntax(sc, "invalid \\uXXXX escape");
            long u = 0;
            for (int k = 2; k < 6; ++k) {
                int h = hex_value(s[sc->i + (size_t)k]);
                if (h < 0) return syntax(sc, "invalid \\uXXXX escape");
                if (sc->canonical && s[sc->i + (size_t)k] >= 'A' && s[sc->i + (size_t)k] <= 'F')
                    return departure(sc, sc->i, "uppercase hex digits in a \\u escape");
                u = u * 16 + h;
            }
            /* ensure_ascii writes printable ASCII as itself and \b \t \n \f \r in their short forms */
            if (sc->canonical && ((u >= 0x20 && u <= 0x7e) || u == 0x08 || u == 0x09 || u == 0x0a || u == 0x0c ||
                                  u == 0x0d))
                return departure(sc, sc->i, "a \\u escape of a character json.dumps writes otherwise");
            sc->i += 6;
        } else if (e == '"' || e == '\\' || e == '/' || e == 'b' || e == 'f' || e == 'n' || e == 'r' || e == 't') {
            if (sc->canonical && e == '/') return departure(sc, sc->i, "an escaped slash \\/");
            sc->i += 2;
        } else {
            return syntax(sc, "invalid \\escape");
        }
    }
    ++sc->i;
    v->kind = TC_JSON_STRING;
    v->begin = b;
    v->end = sc->i;
    emit(sc, s + b, sc->i - b);
    return TC_OK;
}

static int parse_number(scanner *sc, tc_json_value *v) {
    const char *s = sc->s;
    size_t b = sc->i;
    if (s[sc->i] == '-') ++sc->i;
    if (sc->i >= sc->n || !is_digit(s[sc->i])) return syntax(sc, "expecting value");
    size_t int_begin = sc->i;
    if (s[sc->i] == '0') ++sc->i;
    else
        while (sc->i < sc->n && is_digit(s[sc->i])) ++sc->i;
    size_t int_digits = sc->i - int_begin;
    int is_float = 0;
    /* as Python's number pattern -?(0|[1-9]\d*)(\.\d+)?([eE][-+]?\d+)?: a '.' or 'e' not followed by
     * digits ends the number (and the next token is then an error) */
    if (sc->n - sc->i >= 2 && s[sc->i] == '.' && is_digit(s[sc->i + 1])) {
        sc->i += 2;
        while (sc->i < sc->n && is_digit(s[sc->i])) ++sc->i;
        is_float = 1;
    }
    if (sc->i < sc->n && (s[sc->i] == 'e' || s[sc->i] == 'E')) {
        size_t j = sc->i + 1;
        if (j < sc->n && (s[j] == '+' || s[j] == '-')) ++j;
        if (j < sc->n && is_digit(s[j])) {
            sc->i = j;
            while (sc->i < sc->n && is_digit(s[sc->i])) ++sc->i;
            is_float = 1;
        }
    }
    if (!is_float && int_digits > 4300) /* Python's int() refuses longer decimal texts */
        return syntax(sc, "an integer of more than 4300 digits");
    if (sc->canonical) {
        if (!is_float && sc->i - b == 2 && s[b] == '-' && s[b + 1] == '0') return departure(sc, b, "the integer -0");
        if (is_float) {
            double x;
            if (parse_double(s + b, sc->i - b, &x) != 0)
                return tc_fail(sc->msg, TC_NOMEM, "out of memory reading a number of the metadata");
            if (!float_token_is_repr(s + b, sc->i - b, x))
                return departure(sc, b, "a number not written as repr(float)");
        }
    }
    v->kind = TC_JSON_NUMBER;
    v->begin = b;
    v->end = sc->i;
    emit(sc, s + b, sc->i - b);
    return TC_OK;
}

static int parse_word(scanner *sc, const char *word, int kind, tc_json_value *v) {
    size_t len = strlen(word);
    if (sc->n - sc->i < len || memcmp(sc->s + sc->i, word, len) != 0) return syntax(sc, "expecting value");
    v->kind = kind;
    v->begin = sc->i;
    sc->i += len;
    v->end = sc->i;
    emit(sc, word, len);
    return TC_OK;
}

static int parse_object(scanner *sc, int depth, tc_json_value *v) {
    size_t b = sc->i++;
    int rc, emitted = 0, have_prev = 0;
    tc_json_value prev = {0};
    emit(sc, "{", 1);
    skip_ws(sc);
    if (sc->i < sc->n && sc->s[sc->i] == '}') {
        ++sc->i;
    } else {
        for (;;) {
            skip_ws(sc);
            if (sc->i >= sc->n || sc->s[sc->i] != '"')
                return syntax(sc, "expecting property name enclosed in double quotes");
            size_t mark = sc->out_n;
            if (emitted > 0) emit(sc, ",", 1);
            tc_json_value key, value;
            if ((rc = parse_string(sc, &key)) != TC_OK) return rc;
            if (sc->canonical && have_prev && key_compare(sc->s, prev, key) >= 0)
                return departure(sc, key.begin, "keys not sorted or repeated");
            prev = key;
            have_prev = 1;
            skip_ws(sc);
            if (sc->i >= sc->n || sc->s[sc->i] != ':') return syntax(sc, "expecting ':' delimiter");
            ++sc->i;
            emit(sc, ":", 1);
            if ((rc = parse_value(sc, depth + 1, &value)) != TC_OK) return rc;
            int dropped = 0;
            if (depth == 0) {
                if (sc->find_key != NULL && tc_json_string_equals(sc->s, key, sc->find_key)) sc->found = value;
                if (sc->drop_key != NULL && tc_json_string_equals(sc->s, key, sc->drop_key)) dropped = 1;
            }
            if (dropped) sc->out_n = mark; /* the member and the comma before it */
            else ++emitted;
            skip_ws(sc);
            if (sc->i < sc->n && sc->s[sc->i] == ',') {
                ++sc->i;
                continue;
            }
            if (sc->i < sc->n && sc->s[sc->i] == '}') {
                ++sc->i;
                break;
            }
            return syntax(sc, "expecting ',' delimiter");
        }
    }
    emit(sc, "}", 1);
    v->kind = TC_JSON_OBJECT;
    v->begin = b;
    v->end = sc->i;
    return TC_OK;
}

static int parse_array(scanner *sc, int depth, tc_json_value *v) {
    size_t b = sc->i++;
    int rc;
    emit(sc, "[", 1);
    skip_ws(sc);
    if (sc->i < sc->n && sc->s[sc->i] == ']') {
        ++sc->i;
    } else {
        for (;;) {
            tc_json_value item;
            if ((rc = parse_value(sc, depth + 1, &item)) != TC_OK) return rc;
            skip_ws(sc);
            if (sc->i < sc->n && sc->s[sc->i] == ',') {
                ++sc->i;
                emit(sc, ",", 1);
                continue;
            }
            if (sc->i < sc->n && sc->s[sc->i] == ']') {
                ++sc->i;
                break;
            }
            return syntax(sc, "expecting ',' delimiter");
        }
    }
    emit(sc, "]", 1);
    v->kind = TC_JSON_ARRAY;
    v->begin = b;
    v->end = sc->i;
    return TC_OK;
}

/* depth: the number of containers around the value (0 for the top-level value) */
static int parse_value(scanner *sc, int depth, tc_json_value *v) {
    skip_ws(sc);
    if (sc->i >= sc->n) return syntax(sc, "expecting value");
    switch (sc->s[sc->i]) {
    case '"': return parse_string(sc, v);
    case '{':
    case '[':
        if (depth >= TC_JSON_MAX_DEPTH) return syntax(sc, "nesting deeper than 128 levels");
        return sc->s[sc->i] == '{' ? parse_object(sc, depth, v) : parse_array(sc, depth, v);
    case 'n': return parse_word(sc, "null", TC_JSON_NULL, v);
    case 't': return parse_word(sc, "true", TC_JSON_TRUE, v);
    case 'f': return parse_word(sc, "false", TC_JSON_FALSE, v);
    case 'N': return parse_word(sc, "NaN", TC_JSON_NUMBER, v);
    case 'I': return parse_word(sc, "Infinity", TC_JSON_NUMBER, v);
    case '-':
        if (sc->n - sc->i >= 2 && sc->s[sc->i + 1] == 'I') return parse_word(sc, "-Infinity", TC_JSON_NUMBER, v);
        return parse_number(sc, v);
    default:
        if (is_digit(sc->s[sc->i])) return parse_number(sc, v);
        return syntax(sc, "expecting value");
    }
}

static int scan(scanner *sc, tc_json_value *top) {
    int rc;
    skip_ws(sc);
    if ((rc = parse_value(sc, 0, top)) != TC_OK) return rc;
    skip_ws(sc);
    if (sc->i != sc->n) return syntax(sc, "extra data");
    return TC_OK;
}

int tc_json_check_object(const char *text, size_t n, tc_msg msg) {
    scanner sc = {0};
    sc.s = text;
    sc.n = n;
    sc.msg = msg;
    tc_json_value top;
    int rc = scan(&sc, &top);
    if (rc != TC_OK) return rc;
    if (top.kind != TC_JSON_OBJECT) return tc_fail(msg, TC_ERROR, "metadata is not a JSON object");
    return TC_OK;
}

tc_json_value tc_json_member(const char *text, size_t n, const char *key) {
    char scratch[8];
    tc_msg quiet = {scratch, sizeof scratch};
    scanner sc = {0};
    sc.s = text;
    sc.n = n;
    sc.msg = quiet;
    sc.find_key = key;
    tc_json_value top, none = {TC_JSON_ABSENT, 0, 0};
    if (scan(&sc, &top) != TC_OK || top.kind != TC_JSON_OBJECT) return none;
    return sc.found;
}

int tc_json_hashed_text(const char *text, size_t n, const char *drop_key, char *out, size_t *out_n, tc_msg msg) {
    scanner sc = {0};
    sc.s = text;
    sc.n = n;
    sc.msg = msg;
    sc.canonical = 1;
    sc.out = out;
    sc.out_cap = n;
    sc.drop_key = drop_key;
    tc_json_value top;
    *out_n = 0;
    int rc = scan(&sc, &top);
    if (rc != TC_OK) return rc;
    if (top.kind != TC_JSON_OBJECT) return tc_fail(msg, TC_ERROR, "metadata is not a JSON object");
    *out_n = sc.out_n;
    return TC_OK;
}
