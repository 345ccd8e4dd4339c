/*
 * job_runner.c: a request served as a job, chunk by chunk, with the
 * results in memory as a store keeps them (job_runner.h).
 */
#include <stdlib.h>
#include <string.h>

#include "job_runner.h"

typedef struct store {
  const api_job *j;
  char **res;
  size_t *len;
  int stage; /* of the chunks running now */
  int bad_reads;
} store;

/* api_job_inputs.read: only chunks of earlier stages, once stored. */
static int store_read(void *cls, size_t k, char **buf, size_t *len) {
  store *s = cls;
  if (k >= api_job_chunks(s->j) || !s->res[k] ||
      api_job_stage(s->j, k) >= s->stage) {
    s->bad_reads++;
    return -1;
  }
  if (!(*buf = malloc(s->len[k] + 1)))
    return -1;
  memcpy(*buf, s->res[k], s->len[k]);
  (*buf)[s->len[k]] = 0;
  *len = s->len[k];
  return 0;
}

/* The chunks from @a a to @a b (excluded) in @a order, into @a ks. */
static void order_of(size_t a, size_t b, job_order order, unsigned *seed,
                     size_t *ks) {
  size_t n = b - a;
  for (size_t i = 0; i < n; i++)
    ks[i] = order == JOB_REVERSE ? b - 1 - i : a + i;
  if (order != JOB_SHUFFLE)
    return;
  for (size_t i = n; i > 1; i--) { /* Fisher-Yates, a fixed generator */
    *seed = *seed * 1103515245u + 12345u;
    size_t r = (*seed >> 8) % i, t = ks[i - 1];
    ks[i - 1] = ks[r];
    ks[r] = t;
  }
}

/* The visible results in chunk order, as one 200 answer. */
static void concat(const store *s, size_t n, api_response *out) {
  size_t total = 0, at = 0;
  for (size_t k = 0; k < n; k++)
    total += api_job_visible(s->j, k) ? s->len[k] : 0;
  out->status = 200;
  out->content_type = api_job_content_type(s->j);
  out->body = malloc(total + 1);
  for (size_t k = 0; out->body && k < n; k++)
    if (api_job_visible(s->j, k)) {
      memcpy(out->body + at, s->res[k], s->len[k]);
      at += s->len[k];
    }
  if (out->body)
    out->body[total] = 0;
  out->len = total;
}

int job_answer(size_t ep, const char *body, size_t len, const api_limits *lim,
               job_order order, unsigned seed, api_response *out,
               job_trace *t) {
  return job_answer_form(ep, API_FORM_DEFAULT, body, len, lim, order, seed, out,
                         t);
}

int job_answer_form(size_t ep, api_form form, const char *body, size_t len,
                    const api_limits *lim, job_order order, unsigned seed,
                    api_response *out, job_trace *t) {
  api_job *j;
  memset(t, 0, sizeof *t);
  if (api_job_open_form(ep, form, body, len, lim, &j, out) != 0)
    return out->status;
  size_t n = api_job_chunks(j);
  store s = {j, calloc(n, sizeof(char *)), calloc(n, sizeof(size_t)), 0, 0};
  size_t *ks = calloc(n, sizeof *ks);
  api_job_inputs in = {store_read, &s};
  int failed = 0;
  t->opened = 1;
  t->chunks = n;
  t->items = api_job_items(j);
  t->content_type = api_job_content_type(j);
  for (size_t k = 0; k < n; k++)
    t->items_sum += api_job_chunk_items(j, k);
  for (size_t a = 0; a < n && !failed;) {
    size_t b = a;
    s.stage = api_job_stage(j, a);
    while (b < n && api_job_stage(j, b) == s.stage)
      b++;
    order_of(a, b, order, &seed, ks);
    for (size_t i = 0; i < b - a && !failed; i++) {
      api_response r;
      if (api_job_run(j, ks[i], &in, lim, NULL, &r) != 200) {
        *out = r; /* the job fails with it */
        failed = 1;
        break;
      }
      s.res[ks[i]] = r.body; /* stored */
      s.len[ks[i]] = r.len;
    }
    t->stages = s.stage + 1;
    a = b;
  }
  if (!failed)
    concat(&s, n, out);
  t->bad_reads = s.bad_reads;
  for (size_t k = 0; k < n; k++)
    free(s.res[k]);
  free(s.res);
  free(s.len);
  free(ks);
  api_job_free(j);
  return out->status;
}

char *job_blank(const char *s, size_t len, const char *key) {
  size_t kl = strlen(key);
  char *o = malloc(len + 2), *w = o;
  for (size_t i = 0; o && i < len;) {
    if (s[i] != '"' || i + kl + 3 > len || strncmp(s + i + 1, key, kl) ||
        s[i + kl + 1] != '"' || s[i + kl + 2] != ':') {
      *w++ = s[i++];
      continue;
    }
    memcpy(w, s + i, kl + 3);
    w += kl + 3;
    i += kl + 3;
    if (i < len && s[i] == '"') { /* a string: to its closing quote */
      for (i++; i < len && s[i] != '"'; i++)
        i += s[i] == '\\';
      i++;
    } else { /* a number, or null */
      while (i < len && strchr("+-.0123456789eEnul", s[i]))
        i++;
    }
    *w++ = '0';
  }
  if (o)
    *w = 0;
  return o;
}
