/*
 * status.c: status messages and diagnostics.
 */
#include <pthread.h>
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

const char *ss_margin_name(ss_margin_id id) {
  static const char *const NAMES[] = {"",
                                      "slip_below_V",
                                      "overshoot_above_V",
                                      "stick_below_ur",
                                      "stick_above_minus_ur",
                                      "switching",
                                      "transversality",
                                      "duration",
                                      "phase_end",
                                      "grazing",
                                      "ends_early"};
  return (unsigned)id < sizeof NAMES / sizeof NAMES[0] ? NAMES[id] : NULL;
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

const char *ss_version(void) { return SS_VERSION; }

/* GSL keeps one error handler per process, and its default aborts.  Turn it
 * off once, unless the program installed its own before: then put that one
 * back, for the program chose it. */
static void gsl_quiet_once(void) {
  gsl_error_handler_t *previous = gsl_set_error_handler_off();
  if (previous)
    gsl_set_error_handler(previous);
}

void ss_gsl_quiet(void) {
  static pthread_once_t once = PTHREAD_ONCE_INIT;
  pthread_once(&once, gsl_quiet_once);
}
