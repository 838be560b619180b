/* Shared helpers of the native runtime models. */
#include "tc_common.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int tc_fail(tc_msg msg, int status, const char *fmt, ...) {
    if (msg.text != NULL && msg.size > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg.text, msg.size, fmt, ap);
        va_end(ap);
    }
    return status;
}

const char *tc_repr_double(double x, char buf[TC_REPR_SIZE]) {
    for (int prec = 1; prec <= 17; ++prec) {
        snprintf(buf, TC_REPR_SIZE, "%.*g", prec, x);
        if (!isfinite(x) || strtod(buf, NULL) == x) break;
    }
    return buf;
}
