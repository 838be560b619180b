/* The rows of a run's results CSV, formatted in C (C11, standard library only): every value as Python's repr of the
 * double, the shortest decimal text that reads back as the same double (and of those the nearest to it), so that the
 * file is the one tribocosim.cosim.engine.results_csv describes, written without Python work per value.
 */
#ifndef TC_CSV_H
#define TC_CSV_H

#include <stddef.h>

#ifndef TCM_API
#  if defined(_WIN32)
#    define TCM_API __declspec(dllexport)
#  else
#    define TCM_API __attribute__((visibility("default")))
#  endif
#endif

/* The most characters one value takes ("-1.2345678901234567e-308"), and one separator after it. */
#define TCM_CSV_VALUE_MAX 24
#define TCM_CSV_CELL_MAX (TCM_CSV_VALUE_MAX + 1)

/* Format rows of a results CSV into out: for each row r < n_rows, times[r] then values[r n_columns + j], j <
 * n_columns, separated by ',' and ended by '\n'. Writes whole rows while the worst case of one more row,
 * (n_columns + 1) TCM_CSV_CELL_MAX characters, fits into the capacity that is left; returns the rows written and
 * their length in characters in *length (no terminating NUL). */
TCM_API size_t tcm_csv_rows(const double *times, const double *values, size_t n_columns, size_t n_rows, char *out,
                            size_t capacity, size_t *length);

#endif
