/*
 * encode.h: core results to JSON (encode.c), in the units of the request,
 * and a computing answer finished with the echo of its request.
 */
#ifndef SS_API_ENCODE_H
#define SS_API_ENCODE_H

#include <jansson.h>

#include "call.h"
#include "decode.h"
#include "stickslip.h"
#include "stickslip_api.h"

/* A state in the request's units. */
json_t *api__state(const api_params *ap, const double x[4]);

/* Finish a computing answer @a out (consumed): the echo of the request
 * @a x by @a spec with its parameters as "input", the "units" and the
 * "version"; then the 200 response. */
int api__answer(json_t *out, const api_spec *spec, const void *x,
                const api_params *ap, const api_call *c, api_response *resp);

/* The samples of a simulation as columns t, x1, x2, v1, v2, mode, in the
 * units of the request: lazy arrays read from @a r when the answer is
 * written, so @a r must live as long as the answer (it is part of the
 * endpoint's struct). */
json_t *api__samples(const ss_sim_result *r, const api_params *ap,
                     unsigned columns, const api_call *c);

/* The phases of an orbit [{mode, duration}] in the units of the request. */
json_t *api__phases(int n, const ss_mode *modes, const double *tau,
                    const api_params *ap);

/* The Jacobian of the Poincare map, and the whole stability object, in the
 * request's units. */
json_t *api__jacobian(const double J[2][2], const api_params *ap);
json_t *api__stability(const ss_stab *st, const api_params *ap);

#endif
