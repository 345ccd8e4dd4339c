/*
 * job.c: a computing request answered later, as a job cut into chunks
 * (api_job_*, stickslip_api.h), and the status documents a server answers
 * about its jobs.
 *
 * A job is opened as the synchronous request is served up to its
 * computation: the body parsed (api__parse) and decoded by the endpoint's
 * own decode (endpoints.h), so that a bad request is refused at submission
 * with exactly the problem the synchronous request would answer.  Then it
 * is cut.  An endpoint with a row in API_JOB_CUTS below cuts its own jobs
 * (job.h) and keeps its decoded request for its chunks.  Any other is one
 * visible chunk, a single answer: the job keeps the compact text of the
 * request, and its chunk is served from that text by the synchronous path
 * itself (api__handle: parse, decode, run, encode, the time limit), so its
 * result is the synchronous answer by construction, and each run of the
 * chunk decodes its own copy (a chunk whose lease expired may run again
 * while the first run still goes on).
 *
 * Everything here is a function of the request's bytes alone: the same body
 * gives the same cuts in every process, which is what lets any replica
 * compute any chunk of a job it did not open.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "endpoints.h"
#include "job.h"
#include "problem.h"
#include "values.h"
#include "writer.h"

/* The index of each endpoint, in the order of the one list. */
enum {
#define JOB_EP_INDEX(name, method, path, label, cls, dec, run, enc, rel)       \
  JOB_EP_##name,
  API_ENDPOINTS(JOB_EP_INDEX)
#undef JOB_EP_INDEX
      JOB_EP_COUNT
};

/* Each endpoint's decode and release, read from the one list. */
static const struct {
  ep_decode_fn *decode;
  ep_release_fn *release;
} CODEC[JOB_EP_COUNT] = {
#define JOB_EP_CODEC(name, method, path, label, cls, dec, run, enc, rel)       \
  {dec, rel},
    API_ENDPOINTS(JOB_EP_CODEC)
#undef JOB_EP_CODEC
};

/*
 * The endpoints that cut their jobs: one row each, the endpoint's name in
 * API_ENDPOINTS, its cut and run (job.h), the media type of its answer
 * (in its other form, API_FORM_NDJSON, application/x-ndjson), and its
 * open (job.h) or NULL.  An endpoint that is not here answers in
 * one chunk, application/json.
 */
#define API_JOB_CUTS(X)                                                        \
  X(BATCH, ep_batch_job_cut, ep_batch_job_run, "application/x-ndjson",         \
    ep_batch_job_open)                                                         \
  X(MAP, ep_map_job_cut, ep_map_job_run, "application/x-ndjson", NULL)         \
  X(BASINS, ep_basins_job_cut, ep_basins_job_run, "application/json", NULL)

#define JOB_CUT_DECLARE(name, cut, run, media, open)                           \
  ep_job_cut_fn cut;                                                           \
  ep_job_run_fn run;
API_JOB_CUTS(JOB_CUT_DECLARE)
#undef JOB_CUT_DECLARE
ep_job_open_fn ep_batch_job_open;

typedef struct job_row {
  size_t ep;
  ep_job_cut_fn *cut;
  ep_job_run_fn *run;
  const char *media;
  ep_job_open_fn *open;
} job_row;

static const job_row CUTS[] = {
#define JOB_CUT_ROW(name, cut, run, media, open)                               \
  {JOB_EP_##name, cut, run, media, open},
    API_JOB_CUTS(JOB_CUT_ROW)
#undef JOB_CUT_ROW
        {JOB_EP_COUNT, NULL, NULL, NULL, NULL} /* the end */
};

struct api_job {
  size_t ep;
  const job_row *row; /* NULL: a single answer */
  void *x;            /* a row's decoded request, shared by its chunks */
  char *text;         /* a single answer's request, compact */
  size_t len;         /* of text */
  api_job_cut cut;
  long items;
  size_t held;
  api_form form; /* of the answer: a row's x was decoded for it */
};

static const job_row *row_of(size_t ep) {
  for (size_t i = 0; CUTS[i].ep < JOB_EP_COUNT; i++)
    if (CUTS[i].ep == ep)
      return &CUTS[i];
  return NULL;
}

int api__job_cut_alloc(api_job_cut *cut, size_t n, const api_call *c) {
  cut->n = n;
  cut->stage = calloc(n ? n : 1, sizeof *cut->stage);
  cut->items = calloc(n ? n : 1, sizeof *cut->items);
  cut->visible = calloc(n ? n : 1, sizeof *cut->visible);
  if (cut->stage && cut->items && cut->visible)
    return 0;
  free(cut->stage);
  free(cut->items);
  free(cut->visible);
  memset(cut, 0, sizeof *cut);
  return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL,
                   "the job could not be cut: out of memory");
}

void api_job_free(api_job *j) {
  if (!j)
    return;
  if (j->x)
    CODEC[j->ep].release(j->x);
  free(j->text);
  free(j->cut.stage);
  free(j->cut.items);
  free(j->cut.visible);
  free(j);
}

/* What every cut promises its reader (stickslip_api.h): at least one chunk,
 * stages from 0 that never decrease and never skip one, items never
 * negative, and a visible chunk in the last stage (the answer ends
 * there).  A cut that breaks it is a bug of its endpoint. */
static int cut_check(const api_job_cut *cut, const api_call *c) {
  int ok = cut->n >= 1 && cut->stage[0] == 0 && cut->visible[cut->n - 1];
  for (size_t k = 0; ok && k < cut->n; k++)
    ok = cut->items[k] >= 0 && (k == 0 || cut->stage[k] == cut->stage[k - 1] ||
                                cut->stage[k] == cut->stage[k - 1] + 1);
  return ok ? 0
            : api__fail(c->e, API_P_INTERNAL, NULL,
                        "the endpoint cut its job into %zu chunks that do "
                        "not follow the rules of a cut",
                        cut->n);
}

/* A single answer: the compact text of the request, one visible chunk of
 * one item. */
static int cut_single(api_job *j, const json_t *root, const api_call *c) {
  if (!(j->text = api__dump(root, &j->len)))
    return api__fail(c->e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
  if (api__job_cut_alloc(&j->cut, 1, c) != 0)
    return -1;
  j->cut.items[0] = 1;
  j->cut.visible[0] = 1;
  return 0;
}

int api_job_open(size_t index, const char *body, size_t len,
                 const api_limits *lim, api_job **jp, api_response *out) {
  return api_job_open_form(index, API_FORM_DEFAULT, body, len, lim, jp, out);
}

int api_job_open_form(size_t index, api_form form, const char *body, size_t len,
                      const api_limits *lim, api_job **jp, api_response *out) {
  api_err e;
  api_lazies lz = {NULL, 0, 0, 0};
  /* a form the endpoint does not have is its own; the form reaches the
   * endpoint's decode, which keeps it in x for the chunks */
  if (api_negotiate(index, "application/x-ndjson") != form)
    form = API_FORM_DEFAULT;
  api_call c = {lim, NULL, &e, &lz, NULL, form};
  json_t *root = NULL;
  api_job *j = NULL;
  memset(&e, 0, sizeof e);
  memset(out, 0, sizeof *out);
  *jp = NULL;
  const api_endpoint *pub = api_endpoint_at(index);
  if (!pub || pub->run_class == API_RUN_INLINE) {
    api__fail(&e, API_P_NOT_FOUND, NULL,
              "no computing endpoint %zu: only a computing POST runs as a job",
              index);
    goto done;
  }
  if (!(j = calloc(1, sizeof *j))) {
    api__fail(&e, API_P_OUT_OF_MEMORY, NULL, "out of memory");
    goto done;
  }
  j->ep = index;
  j->form = form;
  j->row = row_of(index);
  int opened =
      j->row && j->row->open && body ? j->row->open(body, len, &c, &j->x) : 0;
  if (opened < 0)
    goto done;
  if (!opened && (!(root = api__parse(body ? body : "", len, lim, &e)) ||
                  CODEC[index].decode(root, &c, &j->x) != 0))
    goto done;
  if (!j->row) { /* its chunk decodes its own copy */
    CODEC[index].release(j->x);
    j->x = NULL;
    if (cut_single(j, root, &c) != 0)
      goto done;
  } else if (j->row->cut(j->x, &c, &j->cut) != 0) {
    goto done;
  }
  if (cut_check(&j->cut, &c) != 0)
    goto done;
  for (size_t k = 0; k < j->cut.n; k++)
    j->items += j->cut.items[k];
  /* the decoded request of a row is no larger than the text it came from
   * (its items keep their bodies compact); a single answer keeps its text */
  j->held = sizeof *j + (j->row ? len : j->len) +
            j->cut.n * (sizeof *j->cut.stage + sizeof *j->cut.items + 1);
done:
  api__lazies_free(&lz);
  json_decref(root);
  if (e.set) {
    api_job_free(j);
    api__problem_response(&e, out);
    return -1;
  }
  *jp = j;
  return 0;
}

size_t api_job_chunks(const api_job *j) { return j->cut.n; }

int api_job_stage(const api_job *j, size_t k) {
  return k < j->cut.n ? j->cut.stage[k] : -1;
}

long api_job_chunk_items(const api_job *j, size_t k) {
  return k < j->cut.n ? j->cut.items[k] : 0;
}

long api_job_items(const api_job *j) { return j->items; }

int api_job_visible(const api_job *j, size_t k) {
  return k < j->cut.n && j->cut.visible[k];
}

const char *api_job_content_type(const api_job *j) {
  if (j->form == API_FORM_NDJSON)
    return "application/x-ndjson";
  return j->row ? j->row->media : "application/json";
}

size_t api_job_held(const api_job *j) { return j ? j->held : 0; }

int api_job_run(api_job *j, size_t k, const api_job_inputs *in,
                const api_limits *lim, const api_server_info *srv,
                api_response *out) {
  api_err e;
  api_lazies lz = {NULL, 0, 0, 0};
  api_call c = {lim, srv, &e, &lz, NULL, j->form};
  memset(&e, 0, sizeof e);
  memset(out, 0, sizeof *out);
  if (k >= j->cut.n) {
    api__fail(&e, API_P_INTERNAL, NULL, "the job has no chunk %zu of %zu", k,
              j->cut.n);
  } else if (!j->row) {
    /* the result is stored whole: never a stream */
    api_server_info whole;
    if (srv) {
      whole = *srv;
      whole.stream_above = 0;
      whole.form = j->form;
    }
    api__handle(j->ep, j->text, j->len, lim, srv ? &whole : NULL, out, NULL);
  } else if (j->row->run(j->x, k, in, &c, out) == 0 && out->stream) {
    api__fail(&e, API_P_INTERNAL, NULL,
              "chunk %zu was answered as a stream, which cannot be stored", k);
  }
  api__lazies_free(&lz);
  /* a chunk stopped by a cancel holds what its items answered to the
   * cancel, which is not their answer: it is never a result */
  if (!e.set && out->status == 200 && srv && srv->cancelled &&
      srv->cancelled(srv->cancel_cls))
    api__fail(&e, API_P_CLIENT_CLOSED, NULL,
              "the job was cancelled while chunk %zu ran", k);
  if (e.set) {
    api_response_free(out);
    api__problem_response(&e, out);
  }
  return out->status;
}

/* ---- status documents (OGC API - Processes, Part 1: statusInfo) ----------
 */

/* An instant as RFC 3339 in UTC with milliseconds, e.g.
 * "2026-11-26T21:44:05.123Z"; truncated to the millisecond, so that a later
 * instant is never written earlier. */
static json_t *instant(double epoch) {
  double ms = floor(epoch * 1e3);
  time_t s = (time_t)floor(ms / 1e3);
  struct tm tm;
  char text[40];
  if (!(epoch > 0) || !gmtime_r(&s, &tm))
    return NULL;
  size_t n = strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &tm);
  snprintf(text + n, sizeof text - n, ".%03dZ", (int)(ms - (double)s * 1e3));
  return json_string(text);
}

/* Progress 0-100 from the items done (from the chunks when the job counts
 * no items): 100 only once the job has succeeded, so that the last chunk,
 * which may add no item (a batch's done line), is still to come while it
 * says 99; a job dismissed once every chunk was stored keeps its 100.
 * Monotone while the counts are. */
static int progress(const api_job_info *in) {
  if (in->status && !strcmp(in->status, "dismissed") && in->chunks > 0 &&
      in->chunks_done >= in->chunks)
    return 100;
  long done = in->items > 0 ? in->items_done : in->chunks_done;
  long total = in->items > 0 ? in->items : in->chunks;
  int p =
      total > 0 && done > 0
          ? (int)(100.0 * (double)(done < total ? done : total) / (double)total)
          : 0;
  if (in->status && !strcmp(in->status, "successful"))
    return 100;
  return p < 99 ? p : 99;
}

static json_t *link_to(const char *href, const char *rel, const char *type,
                       const char *title) {
  json_t *l = json_object();
  if (l && (api__set(l, "href", json_string(href)) ||
            api__set(l, "rel", json_string(rel)) ||
            (type && api__set(l, "type", json_string(type))) ||
            api__set(l, "title", json_string(title)))) {
    json_decref(l);
    return NULL;
  }
  return l;
}

static json_t *counts(long done, long total) {
  json_t *o = json_object();
  if (o && (api__set(o, "done", json_integer(done)) ||
            api__set(o, "total", json_integer(total)))) {
    json_decref(o);
    return NULL;
  }
  return o;
}

/* A job's links: itself and its results (OGC's relation for them). */
static json_t *job_links(const char *id) {
  char self[96], results[112];
  snprintf(self, sizeof self, "/jobs/%.64s", id);
  snprintf(results, sizeof results, "/jobs/%.64s/results", id);
  json_t *a = json_array();
  if (a && (json_array_append_new(
                a, link_to(self, "self", "application/json", "this status")) ||
            json_array_append_new(
                a, link_to(results,
                           "http://www.opengis.net/def/rel/ogc/1.0/"
                           "results",
                           NULL, "the results: the answer of the request")))) {
    json_decref(a);
    return NULL;
  }
  return a;
}

/* The status document of @a in; NULL when out of memory. */
static json_t *status_of(const api_job_info *in) {
  static const char *const when[] = {"created", "started", "updated",
                                     "finished"};
  const double at[] = {in->created, in->started, in->updated, in->finished};
  const char *id = in->id ? in->id : "";
  const char *path = in->path ? in->path : "";
  char message[96], process[32];
  /* the process is the endpoint, whatever form its answer takes */
  const char *name = path[0] == '/' ? path + 1 : path;
  snprintf(process, sizeof process, "%.*s", (int)strcspn(name, "?"), name);
  snprintf(message, sizeof message, "%ld of %ld items done", in->items_done,
           in->items);
  json_t *o = json_object();
  int bad = !o || api__set(o, "id", json_string(id)) ||
            api__set(o, "jobID", json_string(id)) ||
            api__set(o, "type", json_string("process")) ||
            api__set(o, "processID", json_string(process)) ||
            api__set(o, "path", json_string(path)) ||
            api__set(o, "status", json_string(in->status ? in->status : "")) ||
            api__set(o, "message",
                     json_string(in->message ? in->message : message)) ||
            api__set(o, "progress", json_integer(progress(in)));
  for (size_t i = 0; !bad && i < sizeof at / sizeof at[0]; i++)
    if (at[i] > 0)
      bad = api__set(o, when[i], instant(at[i]));
  bad = bad || api__set(o, "items", counts(in->items_done, in->items)) ||
        api__set(o, "chunks", counts(in->chunks_done, in->chunks)) ||
        api__set(o, "links", job_links(id));
  if (bad) {
    json_decref(o);
    return NULL;
  }
  return o;
}

/* A 200 application/json answer with the text of @a j (consumed); out of
 * memory when @a j is NULL. */
static int answer(json_t *j, api_response *out) {
  size_t n = 0;
  char *text = j ? api__dump(j, &n) : NULL;
  json_decref(j);
  memset(out, 0, sizeof *out);
  if (!text) {
    api_problem(out, API_P_OUT_OF_MEMORY, "out of memory", NULL, NULL, 0);
    return out->status;
  }
  out->status = 200;
  out->content_type = "application/json";
  out->body = text;
  out->len = n;
  out->held = n;
  return 200;
}

int api_job_status_json(const api_job_info *info, api_response *out) {
  return answer(status_of(info), out);
}

/* A link to the page of @a limit jobs from the @a offset-th. */
static json_t *page(const char *rel, long offset, long limit,
                    const char *title) {
  char href[80];
  snprintf(href, sizeof href, "/jobs?offset=%ld&limit=%ld", offset, limit);
  return link_to(href, rel, "application/json", title);
}

int api_job_list_json(const api_job_info *jobs, size_t n, long offset,
                      long limit, long total, api_response *out) {
  json_t *o = json_object(), *list = json_array(), *links = json_array();
  /* the object owns both arrays from here, also when it cannot take them */
  if (!o) {
    json_decref(list);
    json_decref(links);
  }
  int bad = !o || api__set(o, "jobs", list) ||
            api__set(o, "total", json_integer(total)) ||
            api__set(o, "links", links);
  for (size_t i = 0; !bad && i < n; i++)
    bad = json_array_append_new(list, status_of(&jobs[i])) != 0;
  if (limit < 1)
    limit = 1;
  bad =
      bad ||
      json_array_append_new(links, page("self", offset, limit, "this page")) ||
      (offset + (long)n < total &&
       json_array_append_new(
           links, page("next", offset + (long)n, limit, "the next page"))) ||
      (offset > 0 &&
       json_array_append_new(links,
                             page("prev", offset > limit ? offset - limit : 0,
                                  limit, "the previous page")));
  if (bad) {
    json_decref(o);
    o = NULL;
  }
  return answer(o, out);
}
