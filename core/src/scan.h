/*
 * scan.h: the scan of the period-1 duration equations (scan.c); not
 * installed.
 */
#ifndef SS_SCAN_H
#define SS_SCAN_H

#include "stickslip.h"

/* The roots of the period-1 duration equations of slip-stick (n = 2) or
 * slip-overshoot-stick (n = 3) with every duration in (0, dmax], scanned on
 * a grid of step about h: the durations of each root that may be an
 * orbit into roots (at most max_roots), their number into *n_roots; of
 * the others, the one closest to the rules of its phases among those that
 * fail at a phase's end, and among those that fail inside a phase, into
 * rejected (*n_rejected of them, 0 to 2).  The Newton starts are added to
 * *newton_starts, the cells examined (at every refinement) to *cells.  A
 * cell Newton steps out of is split into quarters and tried again, refine
 * times at most (0 to 3): with less, a scan makes a subset of the Newton
 * starts it makes with more on the same grid, so finds a subset of its
 * roots.  The step is widened to keep at most 1000 cells a side;
 * the step used into *step.
 * stop (if not NULL) is polled once per row of the grid: a non-zero answer
 * ends the scan with SS_ECANCELED and what it found so far.
 * SS_OK, SS_EINVAL, SS_ENOMEM or SS_ECANCELED. */
int ss__scan_period1(const ss_model *m, int n, double dmax, double h,
                     int refine, double (*roots)[3], int max_roots,
                     int *n_roots, double (*rejected)[3], int *n_rejected,
                     int *newton_starts, long *cells, double *step,
                     int (*stop)(void *), void *stop_cls);

#endif
