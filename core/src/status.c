/*
 * status.c: status messages and diagnostics.
 */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "internal.h"

const char *ss_strerror(int status) {
  switch (status) {
#define SS_STATUS_MSG(name, value, msg)                                        \
  case value:                                                                  \
    return msg;
    SS_STATUS_MAP(SS_STATUS_MSG)
#undef SS_STATUS_MSG
  default:
    return "unknown status";
  }
}

const char *ss_status_name(int status) {
  switch (status) {
#define SS_STATUS_NAME(name, value, msg)                                       \
  case value:                                                                  \
    return #name;
    SS_STATUS_MAP(SS_STATUS_NAME)
#undef SS_STATUS_NAME
  default:
    return "UNKNOWN";
  }
}

void ss_diag_clear(ss_diag *d) {
  if (d)
    memset(d, 0, sizeof *d);
}

int ss__fail(ss_diag *d, int status, const char *where, double value,
             const char *fmt, ...) {
  if (d && d->status == 0) {
    va_list ap;
    d->status = status;
    d->value = value;
    snprintf(d->where, sizeof d->where, "%s", where ? where : "");
    va_start(ap, fmt);
    vsnprintf(d->text, sizeof d->text, fmt, ap);
    va_end(ap);
  }
  return status;
}

void ss_gsl_quiet(void) { gsl_set_error_handler_off(); }
