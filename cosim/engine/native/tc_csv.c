/* The rows of a run's results CSV (see tc_csv.h): each double as Python's repr.
 *
 * A positive double x = m 2^e (m < 2^53) reads back from every decimal inside its rounding interval, the reals
 * nearer to x than to its neighbours: [x - u/2, x + u/2] with u = 2^e (the lower half u/4 where m = 2^52 starts a
 * binade), its ends included when m is even (a text on an end reads back as the even neighbour: round half to even).
 * Python's repr (David Gay's dtoa, mode 0) writes the decimal of fewest digits inside it, of those the nearest to x
 * (a tie to the even last digit), as
 *
 *   d.ddde+XX        when the decimal point lies 4 or more places left of the first digit or 17 or more right of it,
 *   ddd.ddd          otherwise, with a ".0" after a whole number.
 *
 * The fewest digits are found exactly with integers: with u' = 2^(e-2) the interval's ends and x are integers times
 * u' (4m - 2 or 4m - 1, 4m, 4m + 2), and they are scaled by 10^-j0, j0 = floor(log10 u') - 1, so that the interval
 * spans more than ten whole units. For -179 <= e - 2 <= 6 (x from 2.4e-38 to 2.3e18) j0 lies in [-55, 0] and
 * X u' 10^-j0 = X 5^-j0 2^(e - 2 - j0) is a product of at most 183 bits shifted right: its whole part fits 64 bits
 * (it is below 100 X < 2^62) and its fraction is known exactly from the bits shifted out. The whole units inside
 * the interval, [L, H], are then divided by 10 while some multiple of the power of ten is left in it; the nearest
 * such multiple to x is the answer. Other doubles (subnormal, tiny, huge) take the C library's correctly rounded
 * printf with 1, 2, ... 17 digits and keep the first text that strtod reads back as x (the nearest of its length,
 * or on the short side of a binade's narrower lower half, its neighbour).
 */
#include "tc_csv.h"

#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the powers 5^0 .. 5^55 as 128-bit numbers {high word, low word} */
#define POW5_COUNT 56

/* a b as a 128-bit number {*hi, *lo} */
static void mul_64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo) {
    const uint64_t mask = UINT64_C(0xffffffff);
    uint64_t a0 = a & mask, a1 = a >> 32, b0 = b & mask, b1 = b >> 32;
    uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    uint64_t mid = (p00 >> 32) + (p01 & mask) + (p10 & mask);
    *lo = (mid << 32) | (p00 & mask);
    *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

static void powers_of_five(uint64_t pow5[POW5_COUNT][2]) {
    pow5[0][0] = 0;
    pow5[0][1] = 1;
    for (int i = 1; i < POW5_COUNT; i++) {
        uint64_t carry, low;
        mul_64(pow5[i - 1][1], 5, &carry, &low);
        pow5[i][0] = pow5[i - 1][0] * 5 + carry;
        pow5[i][1] = low;
    }
}

/* X u' 10^-j0 of the module comment: its whole part and what the bits shifted out hold */
enum { FRACTION_NONE, FRACTION_BELOW_HALF, FRACTION_HALF, FRACTION_ABOVE_HALF };
typedef struct scaled {
    uint64_t whole;
    int fraction;
} scaled;

/* the 192-bit number w (low word first) shifted right by k (1 <= k < 192): whole part and fraction */
static scaled shifted(const uint64_t w[3], unsigned k) {
    scaled out;
    unsigned word = k / 64, shift = k % 64;
    out.whole = w[word] >> shift;
    if (shift && word < 2) out.whole |= w[word + 1] << (64 - shift);
    unsigned half = k - 1;  /* the bit of one half */
    int half_set = (int)((w[half / 64] >> (half % 64)) & 1u), below = 0;
    for (unsigned i = 0; i < half / 64; i++) below |= w[i] != 0;
    if (half % 64) below |= (w[half / 64] & ((UINT64_C(1) << (half % 64)) - 1)) != 0;
    out.fraction = half_set ? (below ? FRACTION_ABOVE_HALF : FRACTION_HALF)
                            : (below ? FRACTION_BELOW_HALF : FRACTION_NONE);
    return out;
}

/* w += sign d {d_hi, d_lo} (192 bits, no overflow or underflow past them) */
static void add_128(uint64_t w[3], uint64_t d_hi, uint64_t d_lo, int negative) {
    if (negative) {
        uint64_t b0 = w[0] < d_lo;
        w[0] -= d_lo;
        uint64_t b1 = w[1] < d_hi || (w[1] == d_hi && b0);
        w[1] -= d_hi + b0;
        w[2] -= b1;
    } else {
        w[0] += d_lo;
        uint64_t c0 = w[0] < d_lo;
        uint64_t sum = w[1] + d_hi;
        uint64_t c1 = sum < d_hi;
        w[1] = sum + c0;
        c1 |= w[1] < c0;
        w[2] += c1;
    }
}

/* The interval's ends and x of the module comment, X in {lo4, x4, hi4}, times 5^a 2^s (5^a = {p_hi, p_lo}); for
 * s >= 0, 5^a < 2^64 and the products are below 2^64. */
static void scale_all(uint64_t lo4, uint64_t x4, uint64_t hi4, uint64_t p_hi, uint64_t p_lo, int s, scaled *lo,
                      scaled *x, scaled *hi) {
    if (s >= 0) {
        lo->whole = (lo4 * p_lo) << s;
        x->whole = (x4 * p_lo) << s;
        hi->whole = (hi4 * p_lo) << s;
        lo->fraction = x->fraction = hi->fraction = FRACTION_NONE;
        return;
    }
    uint64_t w[3], h0, l0, h1, l1;  /* x4 5^a, low word first */
    mul_64(x4, p_lo, &h0, &l0);
    mul_64(x4, p_hi, &h1, &l1);
    w[0] = l0;
    w[1] = h0 + l1;
    w[2] = h1 + (w[1] < h0);
    unsigned k = (unsigned)(-s);
    *x = shifted(w, k);
    uint64_t v[3] = {w[0], w[1], w[2]};
    for (uint64_t i = lo4; i < x4; i++) add_128(v, p_hi, p_lo, 1);  /* lo4 = x4 - 1 or x4 - 2 */
    *lo = shifted(v, k);
    for (uint64_t i = x4; i < hi4; i++) add_128(w, p_hi, p_lo, 0);  /* hi4 = x4 + 2 */
    *hi = shifted(w, k);
}

/* floor(e log10 2) for |e| <= 1100 (661971961083 = floor(log10(2) 2^41); e log10 2 is never within 1e-3 of a whole
 * number there, so the truncated constant does not move the floor) */
static int floor_log10_pow2(int e) {
    const int64_t c = INT64_C(661971961083);
    if (e >= 0) return (int)(((int64_t)e * c) >> 41);
    return -(int)((((int64_t)-e) * c) >> 41) - 1;
}

/* the decimal digits of c (> 0) into digits; returns their number */
static int digits_of(uint64_t c, char *digits) {
    static const char pairs[] = "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
                                "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
                                "8081828384858687888990919293949596979899";
    char reversed[20];
    char *end = reversed + sizeof reversed, *p = end;
    while (c >= 100) {
        unsigned r = (unsigned)(c % 100);
        c /= 100;
        p -= 2;
        memcpy(p, pairs + 2 * r, 2);
    }
    if (c >= 10) {
        p -= 2;
        memcpy(p, pairs + 2 * c, 2);
    } else {
        *--p = (char)('0' + (int)c);
    }
    int n = (int)(end - p);
    memcpy(digits, p, (size_t)n);
    return n;
}

/* The shortest digits of the positive double of these fields, exactly (see the module comment): 0.digits 10^decpt;
 * returns 0 when the double is outside the range this computes. */
static int shortest_exact(unsigned biased, uint64_t fraction, const uint64_t pow5[POW5_COUNT][2], char *digits,
                          int *n, int *decpt) {
    if (biased == 0) return 0;  /* subnormal */
    int e2 = (int)biased - 1075 - 2;  /* u' = 2^e2 */
    if (e2 > 6 || e2 < -179) return 0;
    uint64_t m = fraction | (UINT64_C(1) << 52);
    uint64_t x4 = 4 * m, hi4 = x4 + 2, lo4 = x4 - (fraction == 0 && biased > 1 ? 1 : 2);
    int inclusive = (m & 1) == 0;
    int j0 = floor_log10_pow2(e2) - 1, a = -j0, s = e2 + a;
    scaled lo, x, hi;
    scale_all(lo4, x4, hi4, pow5[a][0], pow5[a][1], s, &lo, &x, &hi);
    uint64_t low = lo.whole + (lo.fraction != FRACTION_NONE || !inclusive);
    uint64_t high = hi.whole - (hi.fraction == FRACTION_NONE && !inclusive);
    int t = 0;  /* the largest t with a multiple of 10^t in [low, high]: [low, high] / 10^t, rounded inwards */
    for (;;) {
        uint64_t next_low = low / 10 + (low % 10 != 0), next_high = high / 10;
        if (next_low > next_high) break;
        low = next_low;
        high = next_high;
        t++;
    }
    uint64_t unit = 1;
    for (int i = 0; i < t; i++) unit *= 10;
    uint64_t c = x.whole / unit, rest = x.whole % unit;
    int up;
    if (t == 0) {
        up = x.fraction == FRACTION_ABOVE_HALF || (x.fraction == FRACTION_HALF && (c & 1));
    } else {
        uint64_t half = unit / 2;
        up = rest > half || (rest == half && (x.fraction != FRACTION_NONE || (c & 1)));
    }
    c += (uint64_t)up;
    if (c < low) c = low;
    if (c > high) c = high;
    *n = digits_of(c, digits);
    *decpt = *n + j0 + t;
    return 1;
}

/* Whether the decimal c 10^p reads back as x. */
static int reads_back(uint64_t c, int p, double x) {
    char text[48];
    snprintf(text, sizeof text, "%" PRIu64 "e%d", c, p);
    return strtod(text, NULL) == x;
}

/* The shortest digits of the positive finite double x with the C library (see the module comment). */
static void shortest_by_printf(double x, char *digits, int *n, int *decpt) {
    char text[48];
    for (int count = 1; count <= 17; count++) {
        snprintf(text, sizeof text, "%.*e", count - 1, x);  /* d.ddde[+-]XX, the nearest of count digits */
        uint64_t c = 0;
        const char *q = text;
        for (; *q && *q != 'e'; q++) {
            if (*q >= '0' && *q <= '9') c = c * 10 + (uint64_t)(*q - '0');
        }
        int p = (int)strtol(q + 1, NULL, 10) - (count - 1);  /* x ~ c 10^p */
        uint64_t first = 1;
        for (int i = 1; i < count; i++) first *= 10;
        uint64_t below = c - 1;
        int below_p = p;
        if (c == first) {  /* the neighbour below 10...0 has a digit more: 99...9 10^(p - 1) */
            below = 10 * first - 1;
            below_p = p - 1;
        }
        uint64_t found = 0;
        if (reads_back(c, p, x)) {
            found = c;
        } else if (count > 1 && reads_back(below, below_p, x)) {
            found = below;
            p = below_p;
        } else if (reads_back(c + 1, p, x)) {
            found = c + 1;
        }
        if (found) {
            while (found % 10 == 0) {
                found /= 10;
                p++;
            }
            *n = digits_of(found, digits);
            *decpt = *n + p;
            return;
        }
    }
    /* not reached: 17 digits always read back */
    snprintf(text, sizeof text, "%.16e", x);
    *n = 1;
    digits[0] = text[0];
    *decpt = 1;
}

/* 0.digits 10^decpt as Python writes it (see the module comment) */
static size_t lay_out(const char *digits, int n, int decpt, char *out) {
    char *p = out;
    if (decpt <= -4 || decpt > 16) {
        *p++ = digits[0];
        if (n > 1) {
            *p++ = '.';
            memcpy(p, digits + 1, (size_t)(n - 1));
            p += n - 1;
        }
        int exponent = decpt - 1;
        unsigned magnitude = (unsigned)(exponent < 0 ? -exponent : exponent);
        *p++ = 'e';
        *p++ = exponent < 0 ? '-' : '+';
        if (magnitude >= 100) *p++ = (char)('0' + magnitude / 100);
        *p++ = (char)('0' + magnitude / 10 % 10);
        *p++ = (char)('0' + magnitude % 10);
    } else if (decpt <= 0) {
        *p++ = '0';
        *p++ = '.';
        for (int i = 0; i < -decpt; i++) *p++ = '0';
        memcpy(p, digits, (size_t)n);
        p += n;
    } else if (decpt >= n) {
        memcpy(p, digits, (size_t)n);
        p += n;
        for (int i = 0; i < decpt - n; i++) *p++ = '0';
        *p++ = '.';
        *p++ = '0';
    } else {
        memcpy(p, digits, (size_t)decpt);
        p += decpt;
        *p++ = '.';
        memcpy(p, digits + decpt, (size_t)(n - decpt));
        p += n - decpt;
    }
    return (size_t)(p - out);
}

/* Python's repr of x into out (at most TCM_CSV_VALUE_MAX characters); returns the length */
static size_t repr_double(double x, const uint64_t pow5[POW5_COUNT][2], char *out) {
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    unsigned biased = (unsigned)((bits >> 52) & 0x7ffu);
    uint64_t fraction = bits & ((UINT64_C(1) << 52) - 1);
    char *p = out;
    if (biased == 0x7ffu) {
        const char *text = fraction ? "nan" : (bits >> 63) ? "-inf" : "inf";
        size_t length = strlen(text);
        memcpy(p, text, length);
        return length;
    }
    if (bits >> 63) *p++ = '-';
    if (biased == 0 && fraction == 0) {
        memcpy(p, "0.0", 3);
        return (size_t)(p - out) + 3;
    }
    char digits[20];
    int n, decpt;
    if (!shortest_exact(biased, fraction, pow5, digits, &n, &decpt)) shortest_by_printf(fabs(x), digits, &n, &decpt);
    return (size_t)(p - out) + lay_out(digits, n, decpt, p);
}

size_t tcm_csv_rows(const double *times, const double *values, size_t n_columns, size_t n_rows, char *out,
                    size_t capacity, size_t *length) {
    uint64_t pow5[POW5_COUNT][2];
    powers_of_five(pow5);
    size_t row_max = (n_columns + 1) * TCM_CSV_CELL_MAX, used = 0, r;
    for (r = 0; r < n_rows && capacity - used >= row_max; r++) {
        char *p = out + used;
        p += repr_double(times[r], pow5, p);
        for (size_t j = 0; j < n_columns; j++) {
            *p++ = ',';
            p += repr_double(values[r * n_columns + j], pow5, p);
        }
        *p++ = '\n';
        used = (size_t)(p - out);
    }
    *length = used;
    return r;
}
