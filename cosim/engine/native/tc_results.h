/* The rows of a run's results CSV in C (C11, standard library only): each double as Python's repr writes it, the
 * shortest decimal text that reads back as the same double, so that the file is the one the Python writer
 * (tribocosim.cosim.engine.results_csv) writes, byte for byte. */
#ifndef TC_RESULTS_H
#define TC_RESULTS_H

#include <stddef.h>

#include "tc_master.h"

/* The text of x as Python's repr(float) gives it ("0.1", "12250.0", "1e-05", "-2.5e+16", "inf", "nan") into out
 * (at least TCM_REPR_SIZE bytes, NUL-terminated); returns its length. */
#define TCM_REPR_SIZE 32
TCM_API size_t tcm_repr(double x, char *out);

/* The CSV lines of n_rows rows "time,v1,...,vn\n" (times[r], then rows[r n_cols .. r n_cols + n_cols - 1]) into out;
 * returns the bytes written, or 0 when they do not fit in capacity bytes. */
TCM_API size_t tcm_format_rows(const double *times, const double *rows, size_t n_rows, size_t n_cols, char *out,
                               size_t capacity);

#endif
