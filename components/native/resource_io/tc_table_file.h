/* The reader of the friction table's resource form: the array file (tc_arrays.h) the Python side writes from a
 * verified table (components/stripdraw/table.py, write_table_resource). */
#ifndef TC_TABLE_FILE_H
#define TC_TABLE_FILE_H

#include <stddef.h>

#include "tc_common.h"
#include "tc_table.h"

/* Read the friction table resource (an array file, tc_table_file.c) at path; a path ending in .npz names the
 * resource beside it ending in .tca. TC_ERROR naming the path when it is missing or malformed, or when the .npz exists
 * and is not the file the resource was made from (its SHA-256 differs from the resource's source_sha256). */
TC_API int tc_table_read(const char *path, tc_table **out, tc_msg msg);

/* The file tc_table_read reads for path (the .tca of a .npz, else path itself) into out (size bytes). */
TC_API void tc_table_resource_path(const char *path, char *out, size_t size);

#endif
