/* SHA-256 (FIPS 180-4, section 6.2): the message padded with a 1 bit, zeros and its length in bits (64-bit big
 * endian) to a multiple of 512 bits; each 512-bit block expanded into 64 words W_t (sigma0, sigma1) and compressed
 * into the eight state words by 64 rounds (Sigma0, Sigma1, Ch, Maj, the constants K_t: the first 32 bits of the
 * fractional parts of the cube roots of the first 64 primes); the digest is the final state, big endian. */
#include "tc_sha256.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

typedef struct sha256 {
    uint32_t h[8];
    uint64_t length; /* bytes hashed */
    unsigned char block[64];
    size_t used; /* bytes in block */
} sha256;

static const uint32_t K[64] = {
    0x428a2f98u, 0x71374491u, 0xb5c0fbcfu, 0xe9b5dba5u, 0x3956c25bu, 0x59f111f1u, 0x923f82a4u, 0xab1c5ed5u,
    0xd807aa98u, 0x12835b01u, 0x243185beu, 0x550c7dc3u, 0x72be5d74u, 0x80deb1feu, 0x9bdc06a7u, 0xc19bf174u,
    0xe49b69c1u, 0xefbe4786u, 0x0fc19dc6u, 0x240ca1ccu, 0x2de92c6fu, 0x4a7484aau, 0x5cb0a9dcu, 0x76f988dau,
    0x983e5152u, 0xa831c66du, 0xb00327c8u, 0xbf597fc7u, 0xc6e00bf3u, 0xd5a79147u, 0x06ca6351u, 0x14292967u,
    0x27b70a85u, 0x2e1b2138u, 0x4d2c6dfcu, 0x53380d13u, 0x650a7354u, 0x766a0abbu, 0x81c2c92eu, 0x92722c85u,
    0xa2bfe8a1u, 0xa81a664bu, 0xc24b8b70u, 0xc76c51a3u, 0xd192e819u, 0xd6990624u, 0xf40e3585u, 0x106aa070u,
    0x19a4c116u, 0x1e376c08u, 0x2748774cu, 0x34b0bcb5u, 0x391c0cb3u, 0x4ed8aa4au, 0x5b9cca4fu, 0x682e6ff3u,
    0x748f82eeu, 0x78a5636fu, 0x84c87814u, 0x8cc70208u, 0x90befffau, 0xa4506cebu, 0xbef9a3f7u, 0xc67178f2u};

static uint32_t rotr(uint32_t x, int n) { return (x >> n) | (x << (32 - n)); }

static void compress(uint32_t h[8], const unsigned char *p) {
    uint32_t w[64], s[8];
    for (int t = 0; t < 16; ++t)
        w[t] = (uint32_t)p[4 * t] << 24 | (uint32_t)p[4 * t + 1] << 16 | (uint32_t)p[4 * t + 2] << 8 |
               (uint32_t)p[4 * t + 3];
    for (int t = 16; t < 64; ++t) {
        const uint32_t s0 = rotr(w[t - 15], 7) ^ rotr(w[t - 15], 18) ^ (w[t - 15] >> 3);
        const uint32_t s1 = rotr(w[t - 2], 17) ^ rotr(w[t - 2], 19) ^ (w[t - 2] >> 10);
        w[t] = w[t - 16] + s0 + w[t - 7] + s1;
    }
    memcpy(s, h, sizeof s);
    for (int t = 0; t < 64; ++t) {
        const uint32_t S1 = rotr(s[4], 6) ^ rotr(s[4], 11) ^ rotr(s[4], 25);
        const uint32_t ch = (s[4] & s[5]) ^ (~s[4] & s[6]);
        const uint32_t t1 = s[7] + S1 + ch + K[t] + w[t];
        const uint32_t S0 = rotr(s[0], 2) ^ rotr(s[0], 13) ^ rotr(s[0], 22);
        const uint32_t maj = (s[0] & s[1]) ^ (s[0] & s[2]) ^ (s[1] & s[2]);
        const uint32_t t2 = S0 + maj;
        s[7] = s[6];
        s[6] = s[5];
        s[5] = s[4];
        s[4] = s[3] + t1;
        s[3] = s[2];
        s[2] = s[1];
        s[1] = s[0];
        s[0] = t1 + t2;
    }
    for (int k = 0; k < 8; ++k) h[k] += s[k];
}

static void start(sha256 *c) {
    static const uint32_t H0[8] = {0x6a09e667u, 0xbb67ae85u, 0x3c6ef372u, 0xa54ff53au,
                                   0x510e527fu, 0x9b05688cu, 0x1f83d9abu, 0x5be0cd19u};
    memcpy(c->h, H0, sizeof H0);
    c->length = 0;
    c->used = 0;
}

static void update(sha256 *c, const unsigned char *p, size_t n) {
    c->length += n;
    while (n > 0) {
        const size_t take = n < 64 - c->used ? n : 64 - c->used;
        memcpy(c->block + c->used, p, take);
        c->used += take;
        p += take;
        n -= take;
        if (c->used == 64) {
            compress(c->h, c->block);
            c->used = 0;
        }
    }
}

static void finish(sha256 *c, char hex[65]) {
    static const char digits[] = "0123456789abcdef";
    const uint64_t bits = c->length * 8u;
    unsigned char pad[72] = {0x80};
    const size_t n = (c->used < 56 ? 56 : 120) - c->used;
    for (int k = 0; k < 8; ++k) pad[n + (size_t)k] = (unsigned char)(bits >> (56 - 8 * k));
    update(c, pad, n + 8);
    for (int k = 0; k < 32; ++k) {
        const unsigned byte = (c->h[k / 4] >> (24 - 8 * (k % 4))) & 0xffu;
        hex[2 * k] = digits[byte >> 4];
        hex[2 * k + 1] = digits[byte & 0xfu];
    }
    hex[64] = '\0';
}

void tc_sha256_bytes(const void *data, size_t n, char hex[65]) {
    sha256 c;
    start(&c);
    update(&c, data, n);
    finish(&c, hex);
}

int tc_sha256_file(const char *path, char hex[65], tc_msg msg) {
    unsigned char buf[16384];
    FILE *f = fopen(path, "rb");
    if (f == NULL) return tc_fail(msg, TC_ERROR, "cannot open %s to compute its SHA-256", path);
    sha256 c;
    start(&c);
    size_t got;
    while ((got = fread(buf, 1, sizeof buf, f)) > 0) update(&c, buf, got);
    const int failed = ferror(f);
    fclose(f);
    if (failed) return tc_fail(msg, TC_ERROR, "cannot read %s to compute its SHA-256", path);
    finish(&c, hex);
    return TC_OK;
}
