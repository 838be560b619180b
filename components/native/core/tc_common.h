/* Shared definitions of the native runtime models (C11, standard library only).
 *
 * Status codes: every function that can fail returns one of them and writes a message that names the
 * quantity, its value and what is allowed into the caller's buffer (tc_msg). A function that returns
 * TC_DISCARD has left its object's state unchanged. No global mutable state: everything an instance
 * needs lives in its own struct.
 */
#ifndef TC_COMMON_H
#define TC_COMMON_H

#include <math.h>
#include <stddef.h>

/* TC_API marks the core functions; they are exported from the library only in test builds
 * (-DTC_EXPORT_CORE), where Python calls them through ctypes. An FMU exports the fmi2 functions only. */
#if defined(TC_EXPORT_CORE)
#  if defined(_WIN32)
#    define TC_API __declspec(dllexport)
#  else
#    define TC_API __attribute__((visibility("default")))
#  endif
#else
#  define TC_API
#endif

enum tc_status {
    TC_OK = 0,
    TC_DISCARD = 1, /* a bad input or a step that cannot be taken; the state is unchanged */
    TC_ERROR = 2,   /* a bad parameter, table or state: the object cannot be used as asked */
    TC_NOMEM = 3    /* an allocation failed */
};

/* A message buffer: the text and its capacity (including the terminating NUL). */
typedef struct tc_msg {
    char *text;
    size_t size;
} tc_msg;

/* printf-style message into msg (truncated to fit); returns status, so that `return tc_fail(...)` reads well. */
int tc_fail(tc_msg msg, int status, const char *fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* A value within this of a bound (relative to the bound) is on it, not beyond it: the ends of a friction table's axes
 * and the declared ranges of parameters and inputs are compared so, because round-off moves a value that is meant to
 * be on a bound to either side of it (12250 N on the 35 x 35 mm pad is 9999999.999999998 Pa, not 10 MPa);
 * components/params.py (BOUND_RTOL, within_bounds) compares the same way. */
#define TC_BOUND_RTOL 1e-9
/* whether x is below the bound lo, or above the bound hi, by more than TC_BOUND_RTOL of the bound */
static inline int tc_below(double x, double lo) { return x < lo - TC_BOUND_RTOL * fabs(lo); }
static inline int tc_above(double x, double hi) { return x > hi + TC_BOUND_RTOL * fabs(hi); }

/* The shortest "%g" text of x that reads back to the same double ("0.08", "12250", "1e-05", "nan", "-inf"), for
 * messages; returns buf. */
#define TC_REPR_SIZE 32
TC_API const char *tc_repr_double(double x, char buf[TC_REPR_SIZE]);

#endif
