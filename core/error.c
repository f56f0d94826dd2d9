/* Status codes and error messages. */
#include "error.h"

#include <stdarg.h>
#include <stdio.h>

const char *emm_strerror(emm_status status)
{
    switch (status) {
    case EMM_OK: return "success";
    case EMM_ERR_IO: return "input/output error";
    case EMM_ERR_FORMAT: return "malformed input";
    case EMM_ERR_CORRUPT: return "corrupted input";
    case EMM_ERR_MESH: return "invalid mesh";
    case EMM_ERR_INVALID: return "invalid value";
    case EMM_ERR_RANGE: return "value out of range";
    case EMM_ERR_NOMEM: return "out of memory";
    case EMM_ERR_UNSUPPORTED: return "unsupported";
    case EMM_STATUS_COUNT: break;
    }
    return "unknown status";
}

const char *emm_version(void)
{
    return EMM_VERSION_STRING;
}

emm_status emm_fail(emm_error *err, emm_status status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
        err->status = status;
    }
    return status;
}

void emm_error_clear(emm_error *err)
{
    if (err) {
        err->status = EMM_OK;
        err->message[0] = '\0';
    }
}
