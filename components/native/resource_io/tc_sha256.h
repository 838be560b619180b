/* SHA-256 (FIPS 180-4) of a file's bytes, for the check that a derived resource still matches its source: the
 * friction table's resource form (.tca) records the SHA-256 of the .npz it was made from (tc_table_file.c). */
#ifndef TC_SHA256_H
#define TC_SHA256_H

#include <stddef.h>

#include "tc_common.h"

/* The SHA-256 of the bytes of the file at path as 64 lowercase hex digits and a NUL into hex. TC_ERROR naming the
 * file when it cannot be opened or read. */
TC_API int tc_sha256_file(const char *path, char hex[65], tc_msg msg);

/* The SHA-256 of n bytes as 64 lowercase hex digits and a NUL into hex. */
TC_API void tc_sha256_bytes(const void *data, size_t n, char hex[65]);

#endif
