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
#include "writer.h"

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

/* The phases of orbit @a o, [{mode, duration}] in the units of the
 * request: a lazy array (api__phases) or its text (api__w_phases); @a o and
 * @a ap are read when the answer is written. */
json_t *api__phases(const api_call *c, const ss_orbit *o, const api_params *ap);
void api__w_phases(api_wbuf *w, const ss_orbit *o, const api_params *ap);

/* The stability object of @a st (eigenvalues, spectral radius, Jacobian of
 * the Poincare map...) in the request's units: an object whose members are
 * written from @a st when the answer is (the caller may add its own after
 * them), or its text. */
json_t *api__stability(const api_call *c, const ss_stab *st,
                       const api_params *ap);
void api__w_stability(api_wbuf *w, const ss_stab *st, const api_params *ap);

/* Numbers, a state in the request's units, as text. */
void api__w_vec(api_wbuf *w, const double *x, int n);
void api__w_state(api_wbuf *w, const api_params *ap, const double x[4]);

/* The tree of the text in @a w (freed): for a document that is kept as a
 * tree or dumped without the answer's lazy values; NULL when out of
 * memory.  Its numbers read back exactly, so it dumps to the same text. */
json_t *api__json_of(api_wbuf *w);

#endif
