/* The array file (.tca): named float64 arrays and texts in one flat little-endian binary file, the one format the
 * native code reads. Written by the Python side (components/native/resource_io/array_file.py, which documents the layout) from the
 * general formats it reads (the friction table's .npz). Entries are looked up by name; unknown ones are skipped.
 */
#ifndef TC_ARRAYS_H
#define TC_ARRAYS_H

#include <stddef.h>
#include <stdint.h>

#include "tc_common.h"

#define TC_ARRAY_FLOAT64 0
#define TC_ARRAY_TEXT 1
#define TC_ARRAY_MAX_NDIM 8

typedef struct tc_array_entry {
    char name[256];
    int kind;                          /* TC_ARRAY_FLOAT64 or TC_ARRAY_TEXT */
    int ndim;                          /* 0 for a scalar or a text */
    uint64_t shape[TC_ARRAY_MAX_NDIM];
    size_t count;                      /* values (float64) or bytes (text) */
    double *values;                    /* float64: count values, C order */
    char *text;                        /* text: count bytes and a terminating NUL */
} tc_array_entry;

typedef struct tc_arrays {
    size_t n;
    tc_array_entry *entries;
} tc_arrays;

/* Read an array file. TC_ERROR naming the file when it cannot be read or is not an array file of format version
 * 1 (magic, sizes, kinds, truncation), TC_NOMEM. what names the file's role in messages ("friction table"). */
TC_API int tc_arrays_read(const char *path, const char *what, tc_arrays **out, tc_msg msg);
TC_API void tc_arrays_free(tc_arrays *a);
/* the entry of that name, NULL if there is none */
TC_API const tc_array_entry *tc_arrays_find(const tc_arrays *a, const char *name);

#endif
