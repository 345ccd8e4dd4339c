/*
 * store_impl.h: what a backend of the job store (store.h) provides, and
 * what store.c does for every backend: results compressed when that pays,
 * errors kept per thread.
 */
#ifndef SS_SERVER_STORE_IMPL_H
#define SS_SERVER_STORE_IMPL_H

#include <stddef.h>

#include "store.h"

/* A backend: the functions of store.h, on its own state.  Results are
 * handed over as stored (compressed or not: @a packed says which) and
 * read back as stored. */
typedef struct store_ops {
  const char *kind;
  void (*close)(void *b);
  int (*submit)(void *b, const store_job *j, const char *body, size_t len,
                const store_chunk *chunks, size_t n);
  int (*get)(void *b, const char *id, store_job *out);
  int (*body)(void *b, const char *id, char **body, size_t *len);
  int (*list)(void *b, long offset, size_t max, store_job *out, size_t *n,
              long *total);
  int (*claim)(void *b, const char *owner, double now, double lease,
               char id[STORE_ID_LEN + 1], long *chunk);
  int (*renew)(void *b, const char *owner, const char *id, long chunk,
               double until);
  int (*complete)(void *b, const char *owner, const char *id, long chunk,
                  const void *result, size_t len, int packed, double now);
  int (*fail)(void *b, const char *id, const char *message, int status,
              const char *problem, size_t len, double now);
  int (*result)(void *b, const char *id, long chunk, char **buf, size_t *len,
                int *packed);
  int (*problem)(void *b, const char *id, int *status, char **body,
                 size_t *len);
  int (*dismiss)(void *b, const char *id, double now);
  int (*counts)(void *b, long by_status[5], long *chunks_pending);
  int (*expire)(void *b, double before, long *n);
} store_ops;

/* Record why a call failed, for store_error() on this thread: printf-like.
 * Returns STORE_ERROR. */
int store__fail(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* The backends: open @a where (the URI without its scheme for sqlite, the
 * whole URI for postgresql): 0 with *b, or STORE_ERROR with the reason in
 * @a why. */
extern const store_ops store__sqlite_ops;
int store__sqlite_open(const char *where, void **b, char *why, size_t n);
extern const store_ops store__pg_ops;
int store__pg_open(const char *uri, void **b, char *why, size_t n);

#endif
