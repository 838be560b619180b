/* SHA-256 (FIPS 180-4, section 6.2), streaming: the digest of the friction table's content hash.
 *
 * table.py (tribocosim/components/stripdraw/table.py, the owner of the table format) hashes the format
 * name, the arrays and the canonical metadata JSON with hashlib.sha256; tc_table_file.c feeds the same
 * bytes through this implementation. Usage: tc_sha256_init, any number of tc_sha256_update,
 * tc_sha256_final; the context holds all state (no globals).
 */
#ifndef TC_SHA256_H
#define TC_SHA256_H

#include <stddef.h>
#include <stdint.h>

#include "tc_common.h"

typedef struct tc_sha256 {
    uint32_t state[8];        /* H0..H7 */
    uint64_t length;          /* bytes hashed so far (the message length appended in the padding) */
    unsigned char block[64];  /* the partial block not yet compressed */
    size_t fill;              /* bytes in block, 0..63 */
} tc_sha256;

TC_API void tc_sha256_init(tc_sha256 *h);
TC_API void tc_sha256_update(tc_sha256 *h, const void *data, size_t n);
/* Pads, writes the 32-byte digest and leaves h re-initialised. */
TC_API void tc_sha256_final(tc_sha256 *h, unsigned char digest[32]);
/* The digest as 64 lowercase hex digits and a NUL (hashlib's hexdigest). */
TC_API void tc_sha256_hex(const unsigned char digest[32], char hex[65]);

#endif
