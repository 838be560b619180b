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
