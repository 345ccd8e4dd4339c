/*
 * modal.h: the closed forms of the motion in each mode and of the switching
 * functions (modal.c); not installed.
 */
#ifndef SS_MODAL_H
#define SS_MODAL_H

#include "stickslip.h"

/* The switching function of @a mode from the anchor state x (local time):
 * slip:      g = x2' - V          (must stay < 0)
 * overshoot: g = V - x2'          (must stay < 0)
 * stick:     g = chi(x2-x1) - ur  (sign = +1) or -ur - chi(x2-x1) (sign = -1)
 */
void ss__switching(const ss_model *m, ss_mode mode, int sign, const double x[4],
                   ss_trig *g);

/* The switching function that ends a phase of @a mode followed by @a next:
 * a stick's side is the next mode's (+ur into slip, -ur into overshoot). */
void ss__end_switching(const ss_model *m, ss_mode mode, ss_mode next,
                       const double x[4], ss_trig *g);

/* The motion in @a mode from the anchor state x, coordinate by coordinate
 * (x1, x2, x1', x2'), as functions of local time: free oscillations are two
 * modal terms about their equilibrium, the stick is a line plus one term
 * (x1, x1') or a line (x2, x2').  They are the closed forms of ss_flow(),
 * written so that their derivatives and bounds on them come for free. */
void ss__coords(const ss_model *m, ss_mode mode, const double x[4],
                ss_trig g[4]);

#endif
