/*
 * call.h: one call of an endpoint, as every step of serving it sees it: the
 * limits, the server's information, the problem being recorded and the
 * answer's lazy arrays; endpoints.c makes one per request.  And the one
 * question the limits and the server answer together: how many threads a
 * computation may run on.
 */
#ifndef SS_API_CALL_H
#define SS_API_CALL_H

#include "problem.h"
#include "stickslip_api.h"

typedef struct api_lazies api_lazies; /* writer.h */

typedef struct api_call {
  const api_limits *lim;
  const api_server_info *srv; /* may be NULL */
  api_err *e;
  api_lazies *lazy; /* the answer's lazy arrays (writer.c) */
  /* may be NULL; set to 1 by a decode whose work is small and bounded
   * (api_server_info.small_only) */
  int *small;
  api_form form; /* the form of the answer asked for (api_negotiate) */
} api_call;

/* The threads a /map or a /basins runs on: --map-threads, no more than the
 * @a useful it can keep busy (rows, cells), and fewer when the server has
 * fewer to spare for the client (api_server_info.threads). */
static inline int api__threads(const api_call *c, long long useful) {
  unsigned want = c->lim->map_threads > 0 ? c->lim->map_threads : 1;
  if (useful < (long long)want)
    want = useful > 1 ? (unsigned)useful : 1;
  if (c->srv && c->srv->threads)
    want = c->srv->threads(c->srv->threads_cls, want);
  return want > 0 ? (int)want : 1;
}

#endif
