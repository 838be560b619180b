/* The nodal-field file of the strip (field_output / field_input): a CSV file, written and read in C.
 *
 * The format is documented, and read in Python, by components/native/resource_io/field_file.py:
 *
 *     # tribocosim strip-draw nodal fields, format 1
 *     # X [m]: X_0,X_1,...,X_M                     (material coordinates of the nodes)
 *     # window [m]: a,b                            (the pad's place in space, [a, a + L_T])
 *     # parameter NAME: VALUE                      (one line per FMU parameter)
 *     time,beta_0,...,beta_M,U_0,...,U_M,contact_0,...,contact_M
 *     t,beta values...,U values...,contact values...        (one row per recorded time)
 *
 * Numbers are printed with 17 significant digits (they read back exactly) and '.' as the decimal point whatever
 * the C locale.
 *
 *   recorder the interval rule `t < last + interval * (1 - 1e-9)` skips a row unless forced; truncate(t)
 *            drops the rows with time > t * (1 + 1e-12) + 1e-15 (a rolled-back step); finish adds the final
 *            row when the model's time is past the last row, then writes;
 *   writing  atomically: a temporary file ".NAME.PID.ID.partial" in the target's folder, renamed into place
 *            (on Windows the target is removed first: rename does not replace there); missing folders are
 *            created (mkdir: the one thing the C standard library cannot do, see tc_fields.c).
 *
 * No global mutable state: a recorder owns its rows; the reader owns nothing after it returns.
 */
#ifndef TC_FIELDS_H
#define TC_FIELDS_H

#include <stddef.h>

#include "tc_common.h"

typedef struct tc_field_recorder tc_field_recorder;

/* A recorder without rows for the field file at path (copied), recording a row when at least interval seconds
 * have passed since the last one. X (n_nodes values) and window are copied; metadata holds the parameter lines'
 * "NAME: VALUE" texts separated by '\n' (copied; control characters other than '\n' are written as '?').
 * TC_ERROR for an interval < 0 or not finite, an empty path or n_nodes = 0; TC_NOMEM. */
TC_API int tc_field_recorder_create(const char *path, double interval, size_t n_nodes, const double *X,
                                    const double window[2], const char *metadata, tc_field_recorder **out,
                                    tc_msg msg);

/* Record the fields (n_nodes values each, copied) at model time t if force, if there is no row yet, or if
 * t >= last + interval * (1 - 1e-9); otherwise nothing happens. TC_NOMEM (the recorder unchanged) if it cannot
 * grow. */
TC_API int tc_field_recorder_record(tc_field_recorder *r, double t, const double *beta, const double *U,
                                    const double *contact, int force, tc_msg msg);

/* Drop the rows recorded after time t: those with time > t * (1 + 1e-12) + 1e-15. */
TC_API void tc_field_recorder_truncate(tc_field_recorder *r, double t);

/* Write the rows recorded so far (atomically; folders created). TC_ERROR naming the path and the system's
 * reason; the recorder is unchanged either way. */
TC_API int tc_field_recorder_write(const tc_field_recorder *r, tc_msg msg);

/* Record the state at time t as the last row if there is no row yet or t is past the last one, then write. */
TC_API int tc_field_recorder_finish(tc_field_recorder *r, double t, const double *beta, const double *U,
                                    const double *contact, tc_msg msg);

/* The number of rows recorded, and the time of the last one (NaN if there is none). */
TC_API size_t tc_field_recorder_rows(const tc_field_recorder *r);
TC_API double tc_field_recorder_last_time(const tc_field_recorder *r);

TC_API void tc_field_recorder_free(tc_field_recorder *r);

/* The last beta row of the field file at path into beta_out (n_nodes values), after checking that the file was
 * written for this mesh: its X has n_nodes values equal to X within 1e-12 m. TC_ERROR naming the path ("field_input
 * = 'PATH' ..."): unreadable, not a field file, no row, another mesh; TC_NOMEM. beta_out is written only on TC_OK. */
TC_API int tc_field_read_initial_beta(const char *path, size_t n_nodes, const double *X, double *beta_out,
                                      tc_msg msg);

#endif
