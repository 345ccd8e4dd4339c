/*
 * internal.h: what the files of the core share (the error record, the
 * clock); not installed.  What one file gives the others is in that file's
 * own header (modal.h for modal.c, ...).
 */
#ifndef SS_INTERNAL_H
#define SS_INTERNAL_H

#include "stickslip.h"

/* Record the first error into @a d (NULL allowed) and return @a status. */
int ss__fail(ss_diag *d, int status, const char *where, double value,
             const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 5, 6)))
#endif
    ;

double ss__now(void); /* monotonic seconds */

#endif
