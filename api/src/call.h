/*
 * call.h: one call of an endpoint, as every step of serving it sees it: the
 * limits, the server's information, the problem being recorded and the
 * answer's lazy arrays.  A type only; endpoints.c makes one per request.
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
} api_call;

#endif
