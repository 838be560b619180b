/* Shared helpers of the native runtime models. */
#include "tc_common.h"

#include <stdarg.h>
#include <stdio.h>

int tc_fail(tc_msg msg, int status, const char *fmt, ...) {
    if (msg.text != NULL && msg.size > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg.text, msg.size, fmt, ap);
        va_end(ap);
    }
    return status;
}
