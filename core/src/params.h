/*
 * params.h: the parameters by id (params.c); not installed.
 */
#ifndef SS_PARAMS_H
#define SS_PARAMS_H

#include "stickslip.h"

/* The member of @a p (@a ph) that parameter @a id names; NULL for an id out
 * of range. */
double *ss__param_ref(ss_params *p, ss_param_id id);
double *ss__phys_ref(ss_physical *ph, ss_phys_id id);

#endif
