/* The rows of a run's results CSV (see tc_results.h).
 *
 * repr(x) in Python is the shortest digit string d1 d2 ... dn with x = 0.d1...dn x 10^decpt read back to x
 * (ties: the one nearest x), written in fixed notation for -4 < decpt <= 16 (with ".0" after an integer) and in
 * exponent notation d1.d2...dn e+XX otherwise. Here the shortest string is found by precision: for n = 1 .. 17 the
 * correctly rounded n-digit string (printf's %.*e) is read back with strtod; the first that gives x is the nearest
 * n-digit string that does, which is repr's. One case differs: when x is a power of two the rounding interval is
 * narrower below x than above it, and an n-digit string above x may read back to x while the nearest one, below,
 * does not; then the next string up is tried too. tests/cosim/test_results_csv.py holds the text to repr's on
 * random doubles, powers of two and subnormals.
 */
#include "tc_results.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The digits of a "%.*e" text ("-d.ddde+XX") into digits (NUL-terminated, no point) and its exponent. */
static int split(const char *text, char *digits, int *exponent) {
    int n = 0;
    const char *p = text;
    if (*p == '-') p++;
    for (; *p && *p != 'e'; p++) {
        if (*p != '.') digits[n++] = *p;
    }
    digits[n] = '\0';
    *exponent = *p == 'e' ? atoi(p + 1) : 0;
    return n;
}

/* Add one unit in the last digit of digits (n of them); returns the new exponent shift (1 when 99..9 -> 100..0). */
static int increment(char *digits, int n) {
    for (int k = n - 1; k >= 0; k--) {
        if (digits[k] < '9') {
            digits[k]++;
            return 0;
        }
        digits[k] = '0';
    }
    memmove(digits + 1, digits, (size_t)n);
    digits[0] = '1';
    digits[n] = '\0';
    return 1;
}

static double read_back(const char *digits, int n, int exponent) {
    char text[48];
    snprintf(text, sizeof text, "%c.%se%d", digits[0], n > 1 ? digits + 1 : "0", exponent);
    return strtod(text, NULL);
}

/* The shortest digits of |x| > 0 (finite) that read back to it, and decpt: |x| = 0.digits x 10^decpt. */
static int shortest(double ax, char *digits, int *decpt) {
    int e2;
    int mantissa_power_of_two = frexp(ax, &e2) == 0.5;
    char text[48];
    for (int n = 1; n <= 17; n++) {
        int exponent;
        snprintf(text, sizeof text, "%.*e", n - 1, ax);
        split(text, digits, &exponent);
        if (read_back(digits, n, exponent) == ax) {
            *decpt = exponent + 1;
            break;
        }
        if (mantissa_power_of_two && read_back(digits, n, exponent) < ax) {
            char up[24];
            memcpy(up, digits, (size_t)n + 1);
            int shift = increment(up, n);
            if (read_back(up, n, exponent + shift) == ax) {
                memcpy(digits, up, (size_t)n + 1);
                digits[n] = '\0';
                *decpt = exponent + shift + 1;
                break;
            }
        }
        *decpt = exponent + 1;  /* n = 17 always reads back */
    }
    int n = (int)strlen(digits);
    while (n > 1 && digits[n - 1] == '0') digits[--n] = '\0';
    return n;
}

TCM_API size_t tcm_repr(double x, char *out) {
    if (isnan(x)) return (size_t)sprintf(out, "nan");
    if (isinf(x)) return (size_t)sprintf(out, x > 0 ? "inf" : "-inf");
    char *p = out;
    if (signbit(x)) *p++ = '-';
    if (x == 0.0) return (size_t)(p - out) + (size_t)sprintf(p, "0.0");
    char digits[24];
    int decpt;
    int n = shortest(fabs(x), digits, &decpt);
    if (decpt > -4 && decpt <= 16) {
        if (decpt <= 0) {
            p += sprintf(p, "0.");
            for (int k = 0; k < -decpt; k++) *p++ = '0';
            p += sprintf(p, "%s", digits);
        } else if (decpt >= n) {
            p += sprintf(p, "%s", digits);
            for (int k = n; k < decpt; k++) *p++ = '0';
            p += sprintf(p, ".0");
        } else {
            memcpy(p, digits, (size_t)decpt);
            p += decpt;
            *p++ = '.';
            p += sprintf(p, "%s", digits + decpt);
        }
    } else {
        int e = decpt - 1;
        *p++ = digits[0];
        if (n > 1) p += sprintf(p, ".%s", digits + 1);
        p += sprintf(p, "e%c%02d", e < 0 ? '-' : '+', abs(e));
    }
    *p = '\0';
    return (size_t)(p - out);
}

TCM_API size_t tcm_format_rows(const double *times, const double *rows, size_t n_rows, size_t n_cols, char *out,
                               size_t capacity) {
    size_t used = 0;
    char value[TCM_REPR_SIZE];
    for (size_t r = 0; r < n_rows; r++) {
        for (size_t j = 0; j <= n_cols; j++) {
            size_t len = tcm_repr(j == 0 ? times[r] : rows[r * n_cols + j - 1], value);
            if (used + len + 1 > capacity) return 0;
            memcpy(out + used, value, len);
            used += len;
            out[used++] = (char)(j == n_cols ? '\n' : ',');
        }
    }
    return used;
}
