/*
 * store.c: the job store's one interface (store.h) over its backends
 * (store_sqlite.c, store_pg.c): the URI's scheme picks the backend; results
 * are compressed (zlib) when they are long enough for it to pay, and read
 * back as they were handed in; the reason of the last failure is kept per
 * thread.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "store_impl.h"

struct store {
  const store_ops *ops;
  void *b;
};

/* Results shorter than this are stored as they are: compressing them saves
 * too little to pay for the work.  Measured on the daemon's answers (zlib
 * level 1, a shared 2-core machine): a 12x10 /map's NDJSON, 146 kB, to 29 %
 * in 3.6 ms (level 6: 25 % in 6.5 ms), one of its lines (1.3 kB) to 43 %
 * in 20 us; a /batch of 32 orbit searches, 267 kB, to 22 % in 3.3 ms
 * (level 6: 17 % in 8.3 ms); a 32x32 /basins, 4.2 kB, to 33 %.  Reading
 * back costs about half of that.  A chunk takes milliseconds to seconds to
 * compute, so level 1 costs it little and stores a quarter to a third.
 * Whole jobs (bench/jobs.py's work, zlib 1.2.13): a 200x200 /map's 44
 * chunks, 6.30 MB, to 0.99 MB (16 %) in 55 ms, read back in 32 ms, on a
 * map of 11-13 s (level 6: 0.91 MB in 205 ms); a /batch of 10 000 orbit
 * searches from a guess, 314 chunks of 11.4 MB, to 1.64 MB (14 %) in
 * 109 ms, read back in 43 ms, on a job of 3.9 s (level 6: 1.38 MB in
 * 307 ms).  A sixth of the disk for under 1 % of a map's time and 3 % of
 * the fastest batch's: the store keeps it; level 6 would cost three times
 * the time for a tenth less. */
#define STORE_PACK_ABOVE 1024

static _Thread_local char last_error[512];

int store__fail(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(last_error, sizeof last_error, fmt, ap);
  va_end(ap);
  return STORE_ERROR;
}

const char *store_error(const store *s) {
  (void)s;
  return last_error[0] ? last_error : "no error";
}

const char *store_status_name(store_status s) {
  static const char *const names[] = {"accepted", "running", "successful",
                                      "failed", "dismissed"};
  return (unsigned)s < sizeof names / sizeof *names ? names[s] : "unknown";
}

int store_open(const char *uri, store **s, char *why, size_t n) {
  *s = NULL;
  store *st = calloc(1, sizeof *st);
  if (!st) {
    snprintf(why, n, "out of memory");
    return STORE_ERROR;
  }
  int rc;
  if (!strncmp(uri, "sqlite:", 7)) {
    st->ops = &store__sqlite_ops;
    rc = store__sqlite_open(uri + 7, &st->b, why, n);
  } else if (!strncmp(uri, "postgresql://", 13) ||
             !strncmp(uri, "postgres://", 11)) {
    st->ops = &store__pg_ops;
    rc = store__pg_open(uri, &st->b, why, n);
  } else {
    snprintf(why, n,
             "the job store \"%s\" is neither sqlite:PATH nor "
             "postgresql://...",
             uri);
    rc = STORE_ERROR;
  }
  if (rc) {
    free(st);
    return STORE_ERROR;
  }
  *s = st;
  return 0;
}

void store_close(store *s) {
  if (!s)
    return;
  s->ops->close(s->b);
  free(s);
}

const char *store_kind(const store *s) { return s->ops->kind; }

int store_submit(store *s, const store_job *j, const char *body, size_t len,
                 const store_chunk *chunks, size_t n) {
  return s->ops->submit(s->b, j, body, len, chunks, n);
}

int store_get(store *s, const char *id, store_job *out) {
  return s->ops->get(s->b, id, out);
}

int store_body(store *s, const char *id, char **body, size_t *len) {
  return s->ops->body(s->b, id, body, len);
}

int store_list(store *s, long offset, size_t max, store_job *out, size_t *n,
               long *total) {
  return s->ops->list(s->b, offset, max, out, n, total);
}

int store_claim(store *s, const char *owner, double now, double lease,
                char id[STORE_ID_LEN + 1], long *chunk) {
  return s->ops->claim(s->b, owner, now, lease, id, chunk);
}

int store_renew(store *s, const char *owner, const char *id, long chunk,
                double until) {
  return s->ops->renew(s->b, owner, id, chunk, until);
}

/* A compressed result: the original length (8 bytes, little-endian), then
 * zlib's stream. */
int store_complete(store *s, const char *owner, const char *id, long chunk,
                   const void *result, size_t len, double now) {
  if (len < STORE_PACK_ABOVE)
    return s->ops->complete(s->b, owner, id, chunk, result, len, 0, now);
  uLongf room = compressBound((uLong)len);
  unsigned char *z = malloc(8 + room);
  if (!z)
    return store__fail("out of memory compressing a result of %zu bytes", len);
  for (int i = 0; i < 8; i++)
    z[i] = (unsigned char)((unsigned long long)len >> (8 * i));
  int rc;
  if (compress2(z + 8, &room, result, (uLong)len, 1) == Z_OK &&
      8 + room < len - len / 8) /* it pays: an eighth saved at least */
    rc = s->ops->complete(s->b, owner, id, chunk, z, 8 + room, 1, now);
  else
    rc = s->ops->complete(s->b, owner, id, chunk, result, len, 0, now);
  free(z);
  return rc;
}

static int unpack(char **buf, size_t *len) {
  const unsigned char *z = (const unsigned char *)*buf;
  if (*len < 8)
    return store__fail("a stored result is damaged (%zu bytes)", *len);
  unsigned long long n = 0;
  for (int i = 0; i < 8; i++)
    n |= (unsigned long long)z[i] << (8 * i);
  char *out = n < ((size_t)1 << 40) ? malloc((size_t)n + 1) : NULL;
  if (!out)
    return store__fail("a stored result of %llu bytes cannot be read", n);
  uLongf got = (uLongf)n;
  if (uncompress((Bytef *)out, &got, z + 8, (uLong)(*len - 8)) != Z_OK ||
      got != n) {
    free(out);
    return store__fail("a stored result is damaged (its zlib stream)");
  }
  out[n] = 0;
  free(*buf);
  *buf = out;
  *len = (size_t)n;
  return 0;
}

int store_result(store *s, const char *id, long chunk, char **buf,
                 size_t *len) {
  int packed = 0;
  int rc = s->ops->result(s->b, id, chunk, buf, len, &packed);
  if (rc || !packed)
    return rc;
  if (unpack(buf, len)) {
    free(*buf);
    *buf = NULL;
    return STORE_ERROR;
  }
  return 0;
}

int store_fail(store *s, const char *id, const char *message, int status,
               const char *problem, size_t len, double now) {
  return s->ops->fail(s->b, id, message, status, problem, len, now);
}

int store_problem(store *s, const char *id, int *status, char **body,
                  size_t *len) {
  return s->ops->problem(s->b, id, status, body, len);
}

int store_dismiss(store *s, const char *id, double now) {
  return s->ops->dismiss(s->b, id, now);
}

int store_counts(store *s, long by_status[5], long *chunks_pending) {
  return s->ops->counts(s->b, by_status, chunks_pending);
}

int store_expire(store *s, double before, long *n) {
  return s->ops->expire(s->b, before, n);
}
