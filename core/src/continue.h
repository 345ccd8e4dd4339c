/*
 * continue.h: what the families (continue.c), the curves of special points
 * (curve.c), branch switching (switch.c) and the study (study.c) share.
 */
#ifndef SS_CONTINUE_H
#define SS_CONTINUE_H

#include "stickslip.h"

/* The slope at the end of phase k of the function that ends it, as
 * ss_orbit_check() takes it (its transversality margin there), by the
 * closed form of the phases from z0. */
double ss__end_slope(const ss_model *m, int n, const ss_mode *modes,
                     const double *tau, const double z0[4], int k);

/* For a margin that can have a zero maximum inside a phase, its index in
 * SS_MARGIN_SLIP_BELOW_V .. SS_MARGIN_STICK_ABOVE_MINUS_UR (0..3); -1 for
 * the others. */
static inline int ss__interior_index(ss_margin_id id) {
  return id >= SS_MARGIN_SLIP_BELOW_V && id <= SS_MARGIN_STICK_ABOVE_MINUS_UR
             ? (int)(id - SS_MARGIN_SLIP_BELOW_V)
             : -1;
}

#endif
