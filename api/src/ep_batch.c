/*
 * ep_batch.c: POST /batch, a list of requests to the computing endpoints.
 *
 * A batch is checked as a whole once (an object with "requests", an array
 * of 1 to max_batch_items items); each item is then checked on its own, so
 * that one bad item is answered by its own line and the others go on.  An
 * item keeps the compact text of its body: it is served exactly as the same
 * body posted to its endpoint would be (api__handle), with that endpoint's
 * limits, and the batch holds no JSON tree while its items run.  Each item
 * is one line of the batch's NDJSON: an item whose answer is NDJSON itself
 * (a /map) has the array of its lines as its body.
 *
 * The server runs the items itself, on its pool, and writes each line as
 * it is done (api_batch_run, api_batch_line); the endpoint's own run below
 * serves them in order, for callers without a pool (the codec's tests, the
 * fuzz target, a program that links the library).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "endpoints.h"
#include "arena.h"
#include "decode.h"
#include "job.h"
#include "problem.h"
#include "scan.h"
#include "writer.h"

typedef struct batch_item {
  char *id;     /* the compact JSON text of its id; "null" when none */
  size_t ep;    /* its endpoint */
  char *body;   /* the text of its body; NULL when the item is bad */
  size_t len;   /* of body */
  int shared;   /* body is a slice of the batch's text, not its own */
  api_err *bad; /* why the item is refused, or NULL */
} batch_item;

struct api_batch {
  batch_item *items;
  size_t n;
  size_t held;
  char *text; /* the body's text, when items' bodies are slices of it */
};

static const char *const ITEM_KEYS = "id, path, body";

size_t api_batch_size(const api_batch *b) { return b ? b->n : 0; }

size_t api_batch_held(const api_batch *b) { return b ? b->held : 0; }

size_t api_batch_endpoint(const api_batch *b, size_t i) {
  return b && i < b->n ? b->items[i].ep : api_endpoint_count();
}

void api_batch_free(api_batch *b) {
  if (!b)
    return;
  for (size_t i = 0; i < b->n; i++) {
    free(b->items[i].id);
    if (!b->items[i].shared)
      free(b->items[i].body);
    free(b->items[i].bad);
  }
  free(b->items);
  free(b->text);
  free(b);
}

/* The computing endpoints, for a message: "/orbit, /simulate, ...". */
static void computing_paths(char *out, size_t n) {
  size_t k = 0;
  out[0] = 0;
  for (size_t i = 0; i < api_endpoint_count(); i++) {
    const api_endpoint *ep = api_endpoint_at(i);
    if (ep->run_class != API_RUN_COMPUTE)
      continue;
    int w = snprintf(out + k, n - k, "%s%s", k ? ", " : "", ep->path);
    if (w < 0 || (size_t)w >= n - k)
      break;
    k += (size_t)w;
  }
}

/* Check item @a v; 0, or -1 with its problem in @a e (pointers relative to
 * the item). */
static int check_item(const json_t *v, batch_item *it, api_err *e) {
  const char *k;
  json_t *f;
  char paths[128];
  it->ep = api_endpoint_count(); /* until its path names one */
  if (!json_is_object(v))
    return api__fail(e, API_P_INVALID_TYPE, NULL,
                     "an item of a batch must be an object with %s", ITEM_KEYS);
  const json_t *id = json_object_get(v, "id");
  if (id && !json_is_string(id) && !json_is_number(id) && !json_is_null(id))
    return api__fail(e, API_P_INVALID_TYPE, "/id",
                     "the id of an item must be a string or a number");
  if (id) {
    size_t n;
    free(it->id);
    if (!(it->id = api__dump(id, &n)))
      return api__fail(e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  }
  json_object_foreach((json_t *)v, k, f) {
    if (strcmp(k, "id") && strcmp(k, "path") && strcmp(k, "body")) {
      char p[96];
      snprintf(p, sizeof p, "/%.80s", k);
      return api__fail(e, API_P_UNKNOWN_FIELD, p,
                       "unknown field \"%.80s\"; an item has %s", k, ITEM_KEYS);
    }
  }
  const json_t *path = json_object_get(v, "path");
  if (!path)
    return api__fail(e, API_P_MISSING_FIELD, "/path",
                     "an item needs \"path\", the endpoint it is for");
  if (!json_is_string(path))
    return api__fail(e, API_P_INVALID_TYPE, "/path",
                     "\"path\" must be a string such as \"/orbit\"");
  const char *ps = json_string_value(path);
  size_t ep;
  int route = api_route("POST", ps, &ep);
  if (route != 200 || api_endpoint_at(ep)->run_class != API_RUN_COMPUTE)
    computing_paths(paths, sizeof paths); /* for the message */
  if (route == 404)
    return api__fail(e, API_P_NOT_FOUND, "/path",
                     "no endpoint %.60s; an item may ask %s", ps, paths);
  if (route != 200 || api_endpoint_at(ep)->run_class != API_RUN_COMPUTE)
    return api__fail(e, API_P_INVALID_VALUE, "/path",
                     "%.60s is not a computing endpoint; an item may ask %s",
                     ps, paths);
  it->ep = ep;
  const json_t *body = json_object_get(v, "body");
  if (!body)
    return api__fail(e, API_P_MISSING_FIELD, "/body",
                     "an item needs \"body\", the request for %s", ps);
  if (!json_is_object(body))
    return api__fail(e, API_P_INVALID_TYPE, "/body",
                     "\"body\" must be an object, the request for %s", ps);
  if (!(it->body = api__dump(body, &it->len)))
    return api__fail(e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  return 0;
}

/* A batch of @a n items, each to be set; NULL when out of memory. */
static api_batch *batch_new(size_t n, const api_call *c) {
  api_batch *b = calloc(1, sizeof *b);
  if (!b || !(b->items = calloc(n, sizeof *b->items))) {
    free(b);
    api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
    return NULL;
  }
  b->n = n;
  return b;
}

/* Item @a i from its JSON @a v: checked, kept, or refused on its own line;
 * -1 only when out of memory. */
static int item_set(api_batch *b, size_t i, const json_t *v,
                    const api_call *c) {
  batch_item *it = &b->items[i];
  api_err e;
  memset(&e, 0, sizeof e);
  if (check_item(v, it, &e) != 0) {
    if (e.kind == API_P_OUT_OF_MEMORY || !(it->bad = malloc(sizeof e)))
      return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
    *it->bad = e;
  }
  b->held += it->len + (it->id ? strlen(it->id) : 0) + sizeof *it;
  return 0;
}

/* An id whose text is the same as its dump: null, a string without
 * escapes, an integer (not -0, which is 0). */
static int id_plain(const api_scan_member *id) {
  const char *v = id->value;
  size_t n = id->value_len;
  if (*v == 'n' || *v == '"')
    return !memchr(v, '\\', n);
  if (n == 2 && !memcmp(v, "-0", 2))
    return 0;
  for (size_t k = *v == '-'; k < n; k++)
    if (v[k] < '0' || v[k] > '9')
      return 0;
  return 1;
}

/* Item @a i from the members @a t of its object, scanned in the batch's
 * text, when they are the plain case: only id, path and body, the id's
 * text its dump (id_plain), the path one of a computing endpoint, the body
 * an object; 1 when set (its body a slice of the text), 0 when not the
 * plain case (left to item_set), -1 when out of memory. */
static int item_plain(api_batch *b, size_t i, const api_scan_top *t,
                      const api_call *c) {
  const api_scan_member *id = NULL, *path = NULL, *body = NULL;
  for (size_t k = 0; k < t->n; k++) {
    const api_scan_member *m = &t->m[k];
    const api_scan_member **to = NULL;
    if (k >= API_SCAN_MEMBERS)
      return 0;
    if (m->key_len == 2 && memcmp(m->key, "id", 2) == 0)
      to = &id;
    else if (m->key_len == 4 && memcmp(m->key, "path", 4) == 0)
      to = &path;
    else if (m->key_len == 4 && memcmp(m->key, "body", 4) == 0)
      to = &body;
    if (!to)
      return 0;
    *to = m;
  }
  char ps[64];
  size_t ep;
  if (!path || !body || *path->value != '"' || *body->value != '{' ||
      path->value_len > sizeof ps + 1 ||
      memchr(path->value, '\\', path->value_len) || (id && !id_plain(id)))
    return 0;
  memcpy(ps, path->value + 1, path->value_len - 2);
  ps[path->value_len - 2] = 0;
  if (api_route("POST", ps, &ep) != 200 ||
      api_endpoint_at(ep)->run_class != API_RUN_COMPUTE)
    return 0;
  batch_item *it = &b->items[i];
  if (id && !(it->id = strndup(id->value, id->value_len)))
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  it->ep = ep;
  it->body = (char *)body->value;
  it->len = body->value_len;
  it->shared = 1;
  b->held += (it->id ? strlen(it->id) : 0) + sizeof *it;
  return 1;
}

/* The batch of the parsed body @a root; NULL with the problem in c->e. */
static api_batch *batch_of(const json_t *root, const api_call *c) {
  const char *k;
  json_t *f;
  json_object_foreach((json_t *)root, k, f) {
    if (strcmp(k, "requests") != 0) {
      char p[96];
      snprintf(p, sizeof p, "/%.80s", k);
      api__fail(c->e, API_P_UNKNOWN_FIELD, p,
                "unknown field \"%.80s\"; a batch has \"requests\" only", k);
      return NULL;
    }
  }
  const json_t *rq = json_object_get(root, "requests");
  if (!rq) {
    api__fail(c->e, API_P_MISSING_FIELD, "/requests",
              "a batch needs \"requests\", an array of {%s}", ITEM_KEYS);
    return NULL;
  }
  if (!json_is_array(rq)) {
    api__fail(c->e, API_P_INVALID_TYPE, "/requests",
              "\"requests\" must be an array of {%s}", ITEM_KEYS);
    return NULL;
  }
  size_t n = json_array_size(rq);
  if (n == 0) {
    api__fail(c->e, API_P_INVALID_VALUE, "/requests",
              "the batch has no requests");
    return NULL;
  }
  if (n > c->lim->max_batch_items) {
    api__limit(c->e, "max_batch_items", (double)c->lim->max_batch_items,
               "/requests", "the batch has %zu requests, over the limit of %zu",
               n, c->lim->max_batch_items);
    return NULL;
  }
  api_batch *b = batch_new(n, c);
  for (size_t i = 0; b && i < n; i++)
    if (item_set(b, i, json_array_get(rq, i), c) != 0) {
      api_batch_free(b);
      return NULL;
    }
  return b;
}

/*
 * A body is read an item at a time when it is of the usual shape,
 *   {"requests": [item, item, ...]}
 * with nothing else and only JSON whitespace between.  A plain item (what
 * api__json_scan vouches for, with only id, path and body, item_plain) is
 * checked in the text without a tree and keeps its body as a slice of the
 * batch's copy of the text, so that its body is parsed once, when the item
 * is served, instead of parsed with the whole body, written back to text
 * and parsed again (jansson's parse of an /orbit item costs a third of its
 * solve).  Another item is parsed alone and kept as the whole body's parse
 * would keep it, its tree freed at once: a job's body may be far larger
 * than a synchronous one (a sweep of a million items), and jansson's tree
 * of it is some twenty times its size (100 000 /orbit items: 13 MB of text,
 * 250 MB of tree).  Any other body, and any item or nesting that jansson or
 * the depth limit would refuse, is left to the whole parse (0), which then
 * answers its problem exactly, line and column.
 */
static const char *skip_ws(const char *p, const char *end) {
  while (p < end && (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r'))
    p++;
  return p;
}

/* The end of the JSON value at @a p, which only delimits it (jansson
 * checks it), and its nesting depth in *depth; NULL when it does not end. */
static const char *value_end(const char *p, const char *end, int *depth) {
  int d = 0;
  *depth = 0;
  for (; p < end; p++) {
    char ch = *p;
    if (ch == '"') {
      for (p++; p < end && *p != '"'; p++)
        p += *p == '\\';
      if (p >= end)
        return NULL;
      if (d == 0)
        return p + 1;
    } else if (ch == '{' || ch == '[') {
      if (++d > *depth)
        *depth = d;
    } else if (ch == '}' || ch == ']') {
      if (d == 0)
        return p;
      if (--d == 0)
        return p + 1;
    } else if (d == 0 && (ch == ',' || ch == ' ' || ch == '\t' || ch == '\n' ||
                          ch == '\r')) {
      return p;
    }
  }
  return d == 0 ? p : NULL;
}

/* Item @a i from its text @a p to @a q: scanned and set without a tree in
 * the plain case (item_plain), or else parsed alone and set as the whole
 * body's parse would set it.  1, 0 when it is not an item that jansson
 * reads (left to the whole parse), -1 when out of memory. */
static int item_of_text(api_batch *b, size_t i, const char *p, const char *q,
                        int scanned, const api_scan_top *t, const api_call *c) {
  int rc = scanned ? item_plain(b, i, t, c) : 0;
  if (rc != 0)
    return rc;
  json_error_t jerr;
  json_t *v = json_loadb(p, (size_t)(q - p), JSON_REJECT_DUPLICATES, &jerr);
  if (!v)
    return 0;
  rc = item_set(b, i, v, c);
  json_decref(v);
  return rc == 0 ? 1 : -1;
}

/* The items of @a body, counted (@a b NULL) or set: 1, 0 when the body is
 * not of the usual shape or an item is not one jansson reads, -1 when out
 * of memory. */
static int items_of_text(const char *body, size_t len, const api_call *c,
                         api_batch *b, size_t *n) {
  static const char HEAD[] = "\"requests\"";
  const char *p = skip_ws(body, body + len), *end = body + len;
  int depth;
  *n = 0;
  if (p == end || *p != '{')
    return 0;
  p = skip_ws(p + 1, end);
  if ((size_t)(end - p) < sizeof HEAD - 1 || memcmp(p, HEAD, sizeof HEAD - 1))
    return 0;
  p = skip_ws(p + sizeof HEAD - 1, end);
  if (p == end || *p != ':')
    return 0;
  p = skip_ws(p + 1, end);
  if (p == end || *p != '[')
    return 0;
  int comma = 0; /* the last thing read was a comma */
  for (p = skip_ws(p + 1, end); p < end && *p != ']';) {
    api_scan_top top;
    /* counting needs only where each item ends */
    const char *q =
        b ? api__json_scan(p, end, c->lim->max_depth - 2, &top) : NULL;
    int scanned = q != NULL;
    if (!q && (!(q = value_end(p, end, &depth)) || q == p ||
               depth + 2 > c->lim->max_depth))
      return 0;
    if (b) {
      int rc = item_of_text(b, *n, p, q, scanned, &top, c);
      if (rc != 1)
        return rc;
    }
    (*n)++;
    p = skip_ws(q, end);
    comma = p < end && *p == ',';
    if (comma)
      p = skip_ws(p + 1, end);
    else if (p == end || *p != ']')
      return 0;
  }
  if (p == end || comma)
    return 0; /* no closing bracket, or a comma before it */
  p = skip_ws(p + 1, end);
  return p < end && *p == '}' && skip_ws(p + 1, end) == end;
}

/* The batch of @a body read an item at a time (items_of_text), its text
 * kept for the items' bodies: 1, 0 when the body is left to the whole
 * parse (another shape, an item jansson does not read, no items or too
 * many: the whole parse then tells which), -1 when out of memory. */
static int batch_of_text(const char *body, size_t len, const api_call *c,
                         api_batch **bp) {
  size_t n, set;
  *bp = NULL;
  if (items_of_text(body, len, c, NULL, &n) != 1 || n == 0 ||
      n > c->lim->max_batch_items)
    return 0;
  api_batch *b = batch_new(n, c);
  if (!b)
    return -1;
  if (!(b->text = malloc(len ? len : 1))) {
    api_batch_free(b);
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  }
  memcpy(b->text, body, len);
  b->held += len;
  int rc = items_of_text(b->text, len, c, b, &set);
  if (rc == 1 && set == n) {
    *bp = b;
    return 1;
  }
  api_batch_free(b);
  return rc < 0 ? -1 : 0;
}

int api_batch_open(const char *body, size_t len, const api_limits *lim,
                   api_batch **b, api_response *out) {
  api_err e;
  api_call c = {lim, NULL, &e, NULL};
  memset(&e, 0, sizeof e);
  memset(out, 0, sizeof *out);
  api_arena_mark mark; /* the items' trees, freed once each is kept */
  api__arena_begin(&mark);
  int rc = body ? batch_of_text(body, len, &c, b) : 0;
  if (rc == 0) {
    json_t *root = api__parse(body ? body : "", len, lim, &e);
    *b = root ? batch_of(root, &c) : NULL;
    json_decref(root);
  }
  api__arena_end(&mark);
  if (!*b) {
    api__problem_response(&e, out);
    return -1;
  }
  return 0;
}

int api_batch_run(api_batch *b, size_t i, const api_limits *lim,
                  const api_server_info *srv, api_response *out) {
  const batch_item *it = &b->items[i];
  memset(out, 0, sizeof *out);
  if (it->bad) {
    api__problem_response(it->bad, out);
    return out->status;
  }
  return api__handle(it->ep, it->body, it->len, lim, srv, out, "/body");
}

/* An NDJSON answer (a /map's lines, written whole by its endpoint) as one
 * JSON value, so that the batch's line stays one line: the array of its
 * lines, whose brackets the batch line's head and tail write.  A line of
 * JSON holds no raw newline (strings escape it), so each newline but the
 * last becomes a comma and the last goes; in place, the bytes it holds no
 * more than they were.  1 when @a r is such an answer. */
static int ndjson_as_array(api_response *r) {
  if (!r->content_type || strcmp(r->content_type, "application/x-ndjson") ||
      r->stream || !r->body || r->len == 0 || r->body[r->len - 1] != '\n')
    return 0;
  r->len--;
  for (size_t j = 0; j < r->len; j++)
    if (r->body[j] == '\n')
      r->body[j] = ',';
  return 1;
}

/* The head of item @a i's line, whose answer is @a item, into @a head (of
 * room for an id and 64 bytes more), its length the return; *tail: what
 * ends the line after the body. */
static size_t line_head(const api_batch *b, size_t i, api_response *item,
                        char *head, size_t n, const char **tail) {
  const char *id = b->items[i].id ? b->items[i].id : "null";
  int lines = ndjson_as_array(item);
  int k =
      snprintf(head, n, "{\"id\":%s,\"index\":%zu,\"status\":%d,\"body\":%s",
               id, i, item->status, lines ? "[" : "");
  *tail = lines ? "]}\n" : "}\n";
  return (size_t)k;
}

static size_t head_room(const api_batch *b, size_t i) {
  return (b->items[i].id ? strlen(b->items[i].id) : 4) + 64;
}

api_stream *api_batch_line(const api_batch *b, size_t i, api_response *item,
                           size_t *held) {
  size_t n = head_room(b, i);
  char *head = malloc(n);
  if (!head) {
    api_response_free(item);
    return NULL;
  }
  const char *tail;
  size_t k = line_head(b, i, item, head, n, &tail);
  *held = k + strlen(tail) + item->held;
  return api__stream_wrap(head, k, item, tail);
}

int api_batch_line_put(const api_batch *b, size_t i, api_response *item,
                       char **buf, size_t *len, size_t *cap) {
  if (item->stream)
    return 0;
  api_wbuf w = {*buf, *len, *cap, 0};
  const char *tail;
  size_t n = head_room(b, i);
  api__w_room(&w, n + item->len + 4);
  if (!w.oom) {
    w.len += line_head(b, i, item, w.p + w.len, n, &tail);
    api__w_put(&w, item->body ? item->body : "", item->len);
    api__w_put(&w, tail, strlen(tail));
  }
  api_response_free(item);
  *buf = w.p;
  *cap = w.cap;
  if (w.oom)
    return -1;
  *len = w.len;
  return 1;
}

void api_batch_done(size_t ok, size_t failed, double seconds,
                    api_response *out) {
  api_wbuf w = {NULL, 0, 0, 0};
  char num[64];
  memset(out, 0, sizeof *out);
  API_W_LIT(&w, "{\"done\":true,\"ok\":");
  api__w_put(&w, num, (size_t)snprintf(num, sizeof num, "%zu", ok));
  API_W_LIT(&w, ",\"failed\":");
  api__w_put(&w, num, (size_t)snprintf(num, sizeof num, "%zu", failed));
  API_W_LIT(&w, ",\"seconds\":");
  api__w_real(&w, seconds);
  API_W_LIT(&w, "}\n");
  out->status = 200;
  out->content_type = "application/x-ndjson";
  out->body = w.p;
  out->len = w.oom ? 0 : w.len;
  out->held = out->len;
}

/* ---- the endpoint, served in order ---------------------------------------
 */

typedef struct batch_x {
  api_batch *b;
  api_wbuf text; /* the lines */
  size_t ok, failed;
  double t0;
} batch_x;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int ep_batch_decode(const json_t *root, const api_call *c, void **xp) {
  batch_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  x->t0 = now();
  return (x->b = batch_of(root, c)) ? 0 : -1;
}

/* Append the whole of stream @a s to @a w, and free it. */
static int drain(api_wbuf *w, api_stream *s) {
  char buf[4096];
  long k;
  while ((k = api_stream_read(s, buf, sizeof buf)) > 0)
    api__w_put(w, buf, (size_t)k);
  api_stream_free(s);
  return k < 0 || w->oom ? -1 : 0;
}

/* Serve item @a i and append its line to @a w: its status, or -1 when out
 * of memory (recorded in c->e). */
static int serve_line(api_batch *b, size_t i, const api_call *c, api_wbuf *w) {
  api_response r;
  size_t held;
  int status = api_batch_run(b, i, c->lim, c->srv, &r);
  int put = api_batch_line_put(b, i, &r, &w->p, &w->len, &w->cap);
  api_stream *line = put == 0 ? api_batch_line(b, i, &r, &held) : NULL;
  if (put < 0 || (put == 0 && (!line || drain(w, line) != 0)))
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                     "the answer could not be written: out of memory");
  return status;
}

int ep_batch_run(void *xp, const api_call *c) {
  batch_x *x = xp;
  for (size_t i = 0; i < x->b->n; i++) {
    int status = serve_line(x->b, i, c, &x->text);
    if (status < 0)
      return -1;
    if (status == 200)
      x->ok++;
    else
      x->failed++;
  }
  api_response done;
  api_batch_done(x->ok, x->failed, now() - x->t0, &done);
  api__w_put(&x->text, done.body ? done.body : "", done.len);
  int oom = !done.len || x->text.oom;
  api_response_free(&done);
  return oom ? api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                         "the answer could not be written: out of memory")
             : 0;
}

int ep_batch_encode(const void *xp, const api_call *c, api_response *out) {
  batch_x *x = (batch_x *)xp; /* its text moves to the answer */
  (void)c;
  out->status = 200;
  out->content_type = "application/x-ndjson";
  out->body = x->text.p;
  out->len = x->text.len;
  out->held = x->text.len;
  x->text = (api_wbuf){NULL, 0, 0, 0};
  return 0;
}

void ep_batch_release(void *xp) {
  batch_x *x = xp;
  if (!x)
    return;
  api_batch_free(x->b);
  free(x->text.p);
  free(x);
}

/* ---- the endpoint as a job -----------------------------------------------
 *
 * A batch's job is cut into chunks of BATCH_CHUNK consecutive items, all in
 * stage 0: a chunk's result is the lines of its items in index order, each
 * as the endpoint above writes it (serve_line), so that the chunks in order
 * are the batch's lines.  A last chunk, in stage 1, writes the done line
 * from their results: the items' statuses are read back from their lines.
 *
 * Why 32 items: a chunk should be long enough that the store's cost for it
 * (a claim, a lease, a result written; milliseconds) is a small share of
 * it, and short enough that progress moves and that a chunk lost with its
 * replica costs little to compute again.  The common item, an /orbit
 * search, takes about 15 ms (2000 of them in 31 s), so 32 of them are about
 * half a second; a batch of /simulate or /stability items is cheaper, one
 * of /map items dearer, and the count is the same for all, so that the
 * same body is cut the same way everywhere.
 */
enum { BATCH_CHUNK = 32 };

ep_job_cut_fn ep_batch_job_cut;
ep_job_run_fn ep_batch_job_run;

ep_job_open_fn ep_batch_job_open;

int ep_batch_job_open(const char *body, size_t len, const api_call *c,
                      void **xp) {
  batch_x *x = api__alloc(sizeof *x, xp, c);
  if (!x)
    return -1;
  int rc = batch_of_text(body, len, c, &x->b);
  if (rc != 1) {
    ep_batch_release(x);
    *xp = NULL;
  }
  return rc;
}

static size_t groups_of(const api_batch *b) {
  return (b->n + BATCH_CHUNK - 1) / BATCH_CHUNK;
}

int ep_batch_job_cut(const void *xp, const api_call *c, api_job_cut *cut) {
  const batch_x *x = xp;
  size_t groups = groups_of(x->b);
  if (api__job_cut_alloc(cut, groups + 1, c) != 0)
    return -1;
  for (size_t k = 0; k < groups; k++) {
    size_t end =
        (k + 1) * BATCH_CHUNK < x->b->n ? (k + 1) * BATCH_CHUNK : x->b->n;
    cut->items[k] = (long)(end - k * BATCH_CHUNK);
    cut->visible[k] = 1;
  }
  cut->stage[groups] = 1; /* the done line, once every line is stored */
  cut->visible[groups] = 1;
  return 0;
}

/* The lines of items @a from to @a to (excluded), in @a out. */
static int chunk_lines(api_batch *b, size_t from, size_t to, const api_call *c,
                       api_response *out) {
  api_wbuf w = {NULL, 0, 0, 0};
  for (size_t i = from; i < to; i++)
    if (serve_line(b, i, c, &w) < 0) {
      free(w.p);
      return -1;
    }
  out->status = 200;
  out->content_type = "application/x-ndjson";
  out->body = w.p ? w.p : calloc(1, 1);
  out->len = w.len;
  out->held = w.len;
  return out->body
             ? 0
             : api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
}

/* Count the statuses of chunk @a k's lines (items @a from to @a to) in
 * @a text: each line is {"id":ID,"index":I,"status":S,... as
 * api_batch_line wrote it, ID the item's own, so that its status is read
 * at a known place without parsing the line's body.  0, or -1 when the
 * text is not those lines. */
static int count_lines(const api_batch *b, size_t from, size_t to,
                       const char *text, size_t len, size_t *ok,
                       size_t *failed) {
  const char *p = text, *end = text + len;
  for (size_t i = from; i < to; i++) {
    const char *id = b->items[i].id ? b->items[i].id : "null";
    char head[64];
    size_t idn = strlen(id);
    int hn = snprintf(head, sizeof head, ",\"index\":%zu,\"status\":", i);
    if ((size_t)(end - p) < 6 + idn + (size_t)hn || memcmp(p, "{\"id\":", 6) ||
        memcmp(p + 6, id, idn) || memcmp(p + 6 + idn, head, (size_t)hn))
      return -1;
    p += 6 + idn + (size_t)hn;
    int status = 0, digits = 0; /* three, as HTTP's */
    while (p < end && *p >= '0' && *p <= '9' && digits++ < 3)
      status = 10 * status + (*p++ - '0');
    if (digits != 3 || (p < end && *p >= '0' && *p <= '9'))
      return -1;
    if (status == 200)
      (*ok)++;
    else
      (*failed)++;
    const char *nl = memchr(p, '\n', (size_t)(end - p));
    if (!nl)
      return -1;
    p = nl + 1;
  }
  return p == end ? 0 : -1;
}

static double epoch_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The done line, from the stored lines of the @a groups chunks before it.
 * Its "seconds" is the time since the job started when the server tells
 * it (in->started), as the synchronous batch's is the time since it
 * started: an item's own compute time is not in its line, which is stored
 * exactly as the synchronous answer has it. */
static int done_line(const api_batch *b, size_t groups,
                     const api_job_inputs *in, const api_call *c,
                     api_response *out) {
  size_t ok = 0, failed = 0;
  for (size_t k = 0; k < groups; k++) {
    char *text = NULL;
    size_t len = 0;
    size_t to = (k + 1) * BATCH_CHUNK < b->n ? (k + 1) * BATCH_CHUNK : b->n;
    if (!in || !in->read || in->read(in->cls, k, &text, &len) != 0)
      return api__fail(c->e, API_P_STORE_UNAVAILABLE, NULL,
                       "the lines of chunk %zu could not be read from the "
                       "job store",
                       k);
    int bad = count_lines(b, k * BATCH_CHUNK, to, text, len, &ok, &failed);
    free(text);
    if (bad)
      return api__fail(c->e, API_P_INTERNAL, NULL,
                       "the stored result of chunk %zu is not the lines of "
                       "its items",
                       k);
  }
  double seconds = in->started > 0 ? epoch_now() - in->started : 0;
  api_batch_done(ok, failed, seconds > 0 ? seconds : 0, out);
  return out->len ? 0
                  : api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
}

int ep_batch_job_run(const void *xp, size_t k, const api_job_inputs *in,
                     const api_call *c, api_response *out) {
  const batch_x *x = xp; /* read only: x->b's items serve themselves */
  size_t groups = groups_of(x->b);
  if (k < groups)
    return chunk_lines(x->b, k * BATCH_CHUNK,
                       (k + 1) * BATCH_CHUNK < x->b->n ? (k + 1) * BATCH_CHUNK
                                                       : x->b->n,
                       c, out);
  return done_line(x->b, groups, in, c, out);
}
