/* The reader of the friction table's resource form: the array file (tc_arrays.h) the Python side writes from a
 * verified table (components/stripdraw/table.py, write_table_resource). */
#ifndef TC_TABLE_FILE_H
#define TC_TABLE_FILE_H

#include "tc_common.h"
#include "tc_table.h"

/* Read the friction table resource (an array file, tc_table_file.c) at path; a path ending in .npz names the
 * resource beside it ending in .tca. TC_ERROR naming the path when it is missing or malformed. */
TC_API int tc_table_read(const char *path, tc_table **out, tc_msg msg);

#endif
