/* Shared helpers of the native runtime models. */
#include "tc_common.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int tc_fail(tc_msg msg, int status, const char *fmt, ...) {
    if (msg.text != NULL && msg.size > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg.text, msg.size, fmt, ap);
        va_end(ap);
    }
    return status;
}

/* ---------------------------------------------------------------------------------------------------
 * Python-like formatting of values for messages
 * ------------------------------------------------------------------------------------------------- */
const char *tc_repr_double(double x, char buf[TC_REPR_SIZE]) {
    if (isnan(x)) return strcpy(buf, "nan");
    if (isinf(x)) return strcpy(buf, x > 0 ? "inf" : "-inf");
    /* the shortest %e representation that reads back to x (what repr() prints) */
    char tmp[40];
    for (int prec = 1; prec <= 17; ++prec) {
        snprintf(tmp, sizeof tmp, "%.*e", prec - 1, x);
        if (strtod(tmp, NULL) == x) break;
    }
    /* digits and decimal exponent of tmp = [-]d[.ddd]e[+-]xx (any decimal-point character) */
    char dig[24];
    int nd = 0, neg = tmp[0] == '-';
    const char *p = tmp + neg;
    for (; *p && *p != 'e' && *p != 'E'; ++p)
        if (*p >= '0' && *p <= '9' && nd < 20) dig[nd++] = *p;
    while (nd > 1 && dig[nd - 1] == '0') --nd;
    int e = (*p) ? atoi(p + 1) : 0;
    char *o = buf;
    if (neg) *o++ = '-';
    if (e >= -4 && e < 16) { /* fixed notation, with ".0" for integral values */
        if (e < 0) {
            *o++ = '0';
            *o++ = '.';
            for (int k = 0; k < -e - 1; ++k) *o++ = '0';
            for (int k = 0; k < nd; ++k) *o++ = dig[k];
        } else {
            for (int k = 0; k <= e; ++k) *o++ = k < nd ? dig[k] : '0';
            *o++ = '.';
            if (nd > e + 1)
                for (int k = e + 1; k < nd; ++k) *o++ = dig[k];
            else
                *o++ = '0';
        }
        *o = '\0';
    } else { /* d.ddde+XX */
        *o++ = dig[0];
        if (nd > 1) {
            *o++ = '.';
            for (int k = 1; k < nd; ++k) *o++ = dig[k];
        }
        snprintf(o, (size_t)(TC_REPR_SIZE - (o - buf)), "e%c%02d", e < 0 ? '-' : '+', e < 0 ? -e : e);
    }
    return buf;
}

const char *tc_repr_string(const char *s, char *buf, size_t size) {
    if (size == 0) return buf;
    char quote = '\'';
    if (s != NULL && strchr(s, '\'') != NULL && strchr(s, '"') == NULL) quote = '"';
    size_t k = 0;
    /* append one piece if it fits (leaving room for the closing quote and NUL) */
#define PUT(str)                                                   \
    do {                                                           \
        size_t len_ = strlen(str);                                 \
        if (k + len_ + 2 > size) goto done;                        \
        memcpy(buf + k, (str), len_);                              \
        k += len_;                                                 \
    } while (0)
    char piece[8] = {quote, '\0'};
    PUT(piece);
    for (const unsigned char *c = (const unsigned char *)(s ? s : ""); *c; ++c) {
        if (*c == '\\') {
            PUT("\\\\");
        } else if (*c == (unsigned char)quote) {
            piece[0] = '\\';
            piece[1] = (char)quote;
            piece[2] = '\0';
            PUT(piece);
        } else if (*c == '\n') {
            PUT("\\n");
        } else if (*c == '\r') {
            PUT("\\r");
        } else if (*c == '\t') {
            PUT("\\t");
        } else if (*c < 0x20 || *c == 0x7f) {
            snprintf(piece, sizeof piece, "\\x%02x", *c);
            PUT(piece);
        } else {
            piece[0] = (char)*c;
            piece[1] = '\0';
            PUT(piece);
        }
    }
    buf[k++] = quote;
done:
#undef PUT
    buf[k < size ? k : size - 1] = '\0';
    return buf;
}

/* NumPy's pairwise summation (numpy/_core/src/umath/loops_utils.h), as np.sum reduces a contiguous
 * float64 array: plain loop below 8 terms, eight interleaved partial sums up to 128, halves above. */
double tc_pairwise_sum(const double *a, size_t n) {
    if (n < 8) {
        double res = 0.0;
        for (size_t i = 0; i < n; ++i) res += a[i];
        return res;
    }
    if (n <= 128) {
        double r[8];
        size_t i;
        for (i = 0; i < 8; ++i) r[i] = a[i];
        for (i = 8; i < n - (n % 8); i += 8)
            for (size_t j = 0; j < 8; ++j) r[j] += a[i + j];
        double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; ++i) res += a[i];
        return res;
    }
    size_t n2 = n / 2;
    n2 -= n2 % 8;
    return tc_pairwise_sum(a, n2) + tc_pairwise_sum(a + n2, n - n2);
}

static double pairwise_in(const double *a, size_t n, long long lo, long long hi) {
    if (hi < 0 || lo >= (long long)n) return 0.0; /* only +0 terms here */
    if (n <= 128) return tc_pairwise_sum(a, n);
    size_t n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise_in(a, n2, lo, hi) + pairwise_in(a + n2, n - n2, lo - (long long)n2, hi - (long long)n2);
}

double tc_pairwise_sum_range(const double *a, size_t n, size_t lo, size_t hi) {
    if (lo > hi) return 0.0;
    return pairwise_in(a, n, (long long)lo, (long long)hi);
}
