/* Internal: filling an emm_error. */
#ifndef EMM_INTERNAL_ERROR_H
#define EMM_INTERNAL_ERROR_H

#include "emm/common.h"

/* Sets err (when not NULL) to `status` and the printf-style message, and
 * returns `status`, so a failing path reads `return emm_fail(err, ...);`. */
emm_status emm_fail(emm_error *err, emm_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Clears err (when not NULL) to EMM_OK and an empty message. */
void emm_error_clear(emm_error *err);

#endif
