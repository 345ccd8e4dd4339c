/*
 * writer.h: the text of an answer (writer.c): compact JSON with the
 * shortest exact digits, lazy arrays written from the core's own arrays,
 * and a large answer as a stream.
 */
#ifndef SS_API_WRITER_H
#define SS_API_WRITER_H

#include <jansson.h>
#include <stddef.h>
#include <string.h>

#include "call.h"
#include "stickslip_api.h"

typedef struct api_wbuf {
  char *p;
  size_t len, cap;
  int oom;
} api_wbuf;

/* Room for @a n more bytes (and a NUL) at b->p + b->len, unless b->oom. */
void api__w_room(api_wbuf *b, size_t n);
/* Append bytes, a JSON string, a number (shortest exact digits; null when
 * not finite).  The bytes are put inline: an answer is hundreds of short
 * pieces, and a call and a memcpy of a few bytes for each cost as much as
 * the digits. */
static inline void api__w_put(api_wbuf *b, const char *s, size_t n) {
  if (b->oom || b->len + n + 1 > b->cap) {
    api__w_room(b, n);
    if (b->oom)
      return;
  }
  memcpy(b->p + b->len, s, n);
  b->len += n;
  b->p[b->len] = 0;
}
void api__w_str(api_wbuf *b, const char *s, size_t n);
void api__w_real(api_wbuf *b, double v);
void api__w_int(api_wbuf *b, long long v); /* the bytes of printf's %lld */
#define API_W_LIT(b, lit) api__w_put(b, lit, sizeof(lit) - 1)

/* A lazy array: n elements, element i written by item() from a, b, k. */
typedef struct api_lazy api_lazy;
typedef void api_item_fn(api_wbuf *w, const api_lazy *l, size_t i);
typedef enum api_lazy_form {
  API_LAZY_ARRAY,  /* [item 0, ..., item n-1] */
  API_LAZY_VALUE,  /* one value, written by item 0 */
  API_LAZY_FIELDS, /* members "k": v, ... of the object it is put in */
} api_lazy_form;
struct api_lazy {
  const json_t *marker;
  api_item_fn *item;
  const void *a, *b;
  int k;
  size_t n;
  api_lazy_form form;
  const void *aux; /* a third thing item() reads (api__raw_aux), or NULL */
};
struct api_lazies {
  api_lazy *v;
  size_t n, cap;
  size_t held; /* bytes of the arrays they are read from */
};

/* The marker of a lazy array of @a n elements, to be put in the answer's
 * tree where the array goes (NULL when out of memory).  What @a a and @a b
 * point to must live as long as the endpoint's struct.  @a held: the bytes
 * of the core arrays it reads, which a streamed answer keeps. */
json_t *api__lazy(const api_call *c, size_t n, api_item_fn *item, const void *a,
                  const void *b, int k, size_t held);
void api__lazies_free(api_lazies *lz);

/* A small value, or some members of object @a o, written by @a item (its
 * index 0) straight from @a a and @a b when the answer is written, rather
 * than built as a tree of values: an orbit's hundred numbers are a few
 * nodes.  What they read must live as long as the answer's text is being
 * written (the endpoint's struct).  api__raw: NULL when out of memory;
 * api__set_fields: 0, or -1 when out of memory. */
json_t *api__raw(const api_call *c, api_item_fn *item, const void *a,
                 const void *b, int k);
int api__set_fields(json_t *o, const api_call *c, api_item_fn *item,
                    const void *a, const void *b, int k);
/* api__raw with @a aux as well, for item() to read as l->aux. */
json_t *api__raw_aux(const api_call *c, api_item_fn *item, const void *a,
                     const void *b, const void *aux);

/* The text of the tree @a j, as the answer's writer writes it (a tree
 * without lazy values). */
void api__w_json(api_wbuf *b, const json_t *j);

/* A 200 application/json answer with the body of @a j (consumed): written
 * whole, or a stream when its lazy arrays are larger than the server's
 * stream_above (the caller then hands the stream the endpoint's struct with
 * api__stream_own). */
int api__json_response(json_t *j, const api_call *c, api_response *out);
void api__stream_own(api_stream *s, void *x, void (*release)(void *));

/* A stream of @a head (malloc'd, consumed), the answer @a r (consumed: its
 * body, or its stream read as it goes) and @a tail (copied); NULL when out
 * of memory (everything given is freed). */
api_stream *api__stream_wrap(char *head, size_t head_len, api_response *r,
                             const char *tail);

/* The compact text of @a j (malloc'd, NUL-terminated, length in *len), with
 * reals in the shortest of 15-17 significant digits that reads back exactly;
 * NULL when out of memory.  Strings must be valid UTF-8 (jansson's own). */
char *api__dump(const json_t *j, size_t *len);

#endif
