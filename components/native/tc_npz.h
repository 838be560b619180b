/* The two containers of a friction table file: the zip archive of numpy's .npz, and the .npy arrays in it.
 *
 * table.py (tribocosim/components/stripdraw/table.py) owns the format; write_table stores it with
 * np.savez: a zip archive (PKWARE APPNOTE 6.3) of uncompressed ("stored") members NAME.npy, each written
 * with force_zip64=True, so sizes and offsets may sit in ZIP64 extra fields. These readers follow what
 * Python's zipfile and numpy.lib.format accept (references: zipfile._EndRecData, ZipFile._RealGetContents,
 * ZipInfo._decodeExtra, ZipFile.open; numpy.lib.format.read_array) and refuse, with a message, what the
 * native reader does not handle: compressed or encrypted members.
 *
 * Every size and offset read from the file is checked against the buffer before use. Messages name the
 * member but not the file; the caller adds the path.
 */
#ifndef TC_NPZ_H
#define TC_NPZ_H

#include <stddef.h>
#include <stdint.h>

#include "tc_common.h"

/* A zip archive held in memory. */
typedef struct tc_zip {
    const unsigned char *data; /* the whole file */
    size_t size;
    size_t cd_begin;    /* where the central directory starts in data */
    size_t cd_size;     /* its size in bytes (cd_begin + cd_size <= size) */
    uint64_t cd_offset; /* its offset as recorded; local-header offsets are relative to the same origin, which
                           is cd_begin - cd_offset when bytes were prepended to the archive (as zipfile allows) */
} tc_zip;

/* A member's bytes: data[offset .. offset + size) of the archive. */
typedef struct tc_zip_member {
    size_t offset;
    size_t size;
} tc_zip_member;

/* Finds the end-of-central-directory record (and the ZIP64 one when present) and checks every central
 * directory entry as zipfile does when it opens an archive. TC_ERROR with a message if data is not a
 * readable zip archive. */
TC_API int tc_zip_open(tc_zip *zip, const unsigned char *data, size_t size, tc_msg msg);

/* The member called name (the last entry of that name, as zipfile keeps): its local header is checked,
 * and the member must be stored uncompressed, unencrypted, lie inside the file and match its CRC-32. */
TC_API int tc_zip_find(const tc_zip *zip, const char *name, tc_zip_member *member, tc_msg msg);

/* 1 if the central directory of an archive that tc_zip_open accepted has an entry called name (zipfile's
 * namelist, which numpy's NpzFile consults first: a missing member is its KeyError), else 0. Nothing about
 * the entry is checked: tc_zip_find does that. */
TC_API int tc_zip_has(const tc_zip *zip, const char *name);

#define TC_NPY_MAX_DIMS 32

/* The header of a .npy array (NEP 1 / numpy.lib.format, versions 1.0, 2.0 and 3.0). */
typedef struct tc_npy {
    char descr[64];          /* the dtype string, e.g. "<f8", "<U43914" */
    int fortran_order;       /* 1 if the data are in Fortran order */
    size_t ndim;
    uint64_t shape[TC_NPY_MAX_DIMS];
    uint64_t count;          /* number of elements: the product of shape (1 for a 0-d array) */
    size_t data_offset;      /* where the array data start, from the beginning of the .npy bytes */
} tc_npy;

/* Parses the header of the .npy bytes p[0..n) of member `name` (for messages). The header is a Python
 * dict literal; this parser takes the forms numpy writes ({'descr': '<f8', 'fortran_order': False,
 * 'shape': (6, 4, 7), } padded with spaces), in any key order and spacing, and refuses the rest. */
TC_API int tc_npy_parse(const unsigned char *p, size_t n, const char *name, tc_npy *npy, tc_msg msg);

/* The shape as Python prints the tuple: "()", "(6,)", "(6, 4, 7)"; this text is hashed by table.py. */
void tc_npy_shape_repr(const tc_npy *npy, char *buf, size_t size);

#endif
