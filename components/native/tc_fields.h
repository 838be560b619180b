/* The nodal-field file of the strip (field_output / field_input), written and read in C.
 *
 * The format's owner is tribocosim/components/stripdraw/fields.py (write_fields, read_fields,
 * read_initial_beta, FieldRecorder); this file follows it rule for rule:
 *
 *   file     a zip archive of stored (uncompressed) members, byte for byte as np.savez writes it (ZIP64 local
 *            headers as force_zip64 writes them, DOS date 1980-01-01, ZIP64 central-directory fields and end
 *            records only past zipfile's ZIP64_LIMIT of 2**31 - 1 bytes);
 *   members  time.npy (n,) '<f8', X.npy (m,), beta.npy / U.npy / contact.npy (n, m) C order, window.npy (2,),
 *            metadata.npy a 0-d '<U<k>' array holding the JSON text (UTF-32LE), in that order; NPY 1.0
 *            headers padded as numpy pads them;
 *   recorder the interval rule `t < last + interval * (1 - 1e-9)` skips a row unless forced; truncate(t)
 *            drops the rows with time > t * (1 + 1e-12) + 1e-15 (a rolled-back step); finish adds the final
 *            row when the model's time is past the last row, then writes;
 *   writing  atomically: a temporary file ".NAME.PID.ID.partial" in the target's folder, renamed into place
 *            (on Windows the target is removed first: rename does not replace there); missing folders are
 *            created (mkdir: the one thing the C standard library cannot do, see tc_fields.c).
 *
 * Messages name the quantity and the path as the Python module does (paths as Python's repr prints them).
 * No global mutable state: a recorder owns its rows; the reader owns nothing after it returns.
 */
#ifndef TC_FIELDS_H
#define TC_FIELDS_H

#include <stddef.h>

#include "tc_common.h"

/* Rows of nodal fields (beta, U, contact) at the recorded times, written as one field file. */
typedef struct tc_field_recorder tc_field_recorder;

/* A recorder without rows for the field file at path (copied), recording a row when at least interval
 * seconds have passed since the last one. X (n_nodes values) and window ([a, a + L_T]) are copied;
 * metadata_json is the text of the "metadata" member: a JSON object in ASCII (json.dumps(parameters,
 * sort_keys=True) in the Python FMU), checked here so that a written file always reads back. TC_ERROR for an
 * interval < 0 or NaN ("field_output_interval = ... s must be >= 0", FieldRecorder.start's message) or
 * infinite (the FMU parameter check's message), an empty path, n_nodes = 0 or a metadata text that is not
 * an ASCII JSON object; TC_NOMEM. *out is NULL unless TC_OK. */
TC_API int tc_field_recorder_create(const char *path, double interval, size_t n_nodes, const double *X,
                                    const double window[2], const char *metadata_json, tc_field_recorder **out,
                                    tc_msg msg);

/* Record the fields (n_nodes values each, copied) at model time t if force, if there is no row yet, or if
 * t >= last + interval * (1 - 1e-9) (FieldRecorder.record); otherwise nothing happens. Storage grows by
 * doubling. TC_NOMEM (the recorder unchanged) if it cannot grow. */
TC_API int tc_field_recorder_record(tc_field_recorder *r, double t, const double *beta, const double *U,
                                    const double *contact, int force, tc_msg msg);

/* Drop the rows recorded after time t: those with time > t * (1 + 1e-12) + 1e-15 (FieldRecorder.truncate). */
TC_API void tc_field_recorder_truncate(tc_field_recorder *r, double t);

/* Write the rows recorded so far to the recorder's path (atomically; folders created). With no row the file
 * holds time (0,) and beta, U, contact (0, n_nodes). TC_ERROR with a message naming the path and the system's
 * reason ("[Errno 13] Permission denied: '...'"), TC_NOMEM. The recorder is unchanged either way. */
TC_API int tc_field_recorder_write(const tc_field_recorder *r, tc_msg msg);

/* FieldRecorder.finish: record the model's state at time t as the last row if there is no row yet or t is
 * past the last one, then write the file. */
TC_API int tc_field_recorder_finish(tc_field_recorder *r, double t, const double *beta, const double *U,
                                    const double *contact, tc_msg msg);

/* The number of rows recorded, and the time of the last one (NaN if there is none). */
TC_API size_t tc_field_recorder_rows(const tc_field_recorder *r);
TC_API double tc_field_recorder_last_time(const tc_field_recorder *r);

TC_API void tc_field_recorder_free(tc_field_recorder *r);

/* The writer underneath (write_fields): n_rows times, n_nodes values of X, the (n_rows, n_nodes) row-major
 * arrays beta, U and contact (which may be NULL when n_rows = 0), the window and the metadata JSON text
 * (ASCII, written as given), to path, atomically, folders created. Error messages start with
 * "field_output = 'PATH' cannot be written: ". */
TC_API int tc_fields_write(const char *path, size_t n_rows, size_t n_nodes, const double *time, const double *X,
                           const double *beta, const double *U, const double *contact, const double window[2],
                           const char *metadata_json, tc_msg msg);

/* read_initial_beta: the last beta row of the field file at path into beta_out (n_nodes values), after the
 * checks of the Python reader and with its messages:
 *   - unreadable: "field_input = 'PATH' cannot be read as a field_output file: REASON", REASON as Python's
 *     exception prints it where the native reader can tell the same story ("[Errno 2] No such file or
 *     directory: 'PATH'", "'X is not a file in the archive'", "EOF: reading array data, expected ..."),
 *     otherwise the zip/npy reader's own words (tc_npz.h; Python lets zipfile's BadZipFile through there);
 *     members other than '<f8' are refused (write_fields writes float64 only; Python would convert them);
 *   - "field_input = 'PATH': beta has shape (..), X has M nodes" unless beta is (n >= 1, M) and X has M values;
 *   - "field_input = 'PATH' was written for another mesh (M nodes over [X0, Xm] m; this strip has N nodes
 *     over [x0, xn] m): use the same geometry and n_elements" unless the file's X equals the given one to
 *     an absolute 1e-12 (np.allclose(rtol=0, atol=1e-12)); bounds formatted as Python's :g.
 * TC_ERROR, TC_NOMEM; beta_out is written only on TC_OK. */
TC_API int tc_field_read_initial_beta(const char *path, size_t n_nodes, const double *X, double *beta_out,
                                      tc_msg msg);

/* format(x, 'g') as Python prints it ("0.35", "1e-05", "-0", "nan", "inf"), independent of the C locale;
 * returns buf. */
#define TC_FORMAT_G_SIZE 32
TC_API const char *tc_format_g(double x, char buf[TC_FORMAT_G_SIZE]);

#endif
