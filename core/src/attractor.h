/*
 * attractor.h: the attractor finder with a poll (attractor.c); not
 * installed.
 */
#ifndef SS_ATTRACTOR_H
#define SS_ATTRACTOR_H

#include "stability.h"
#include "stickslip.h"

/* ss_attractor_from() polling @a poll (NULL: never) at each event:
 * SS_ECANCELED when it says stop. */
int ss__attractor_from(const ss_model *m, const double s0[2], int max_turns,
                       int max_period, ss__poll *poll, ss_attractor *a);

#endif
