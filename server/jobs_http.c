/*
 * jobs_http.c: jobs over HTTP (OGC API - Processes - Part 1: Core, and
 * RFC 7240's Prefer).
 *
 *   POST <a computing endpoint> with Prefer: respond-async
 *       the request checked as the synchronous one would be (its problems
 *       answered at once), stored as a job cut into chunks, and answered
 *       201 Created, Location: /jobs/{id}, Preference-Applied:
 *       respond-async, with the job's status document
 *   GET /jobs?limit=&offset=       the jobs, newest first, a page
 *   GET /jobs/{id}                 its status document
 *   DELETE /jobs/{id}              dismissed: its work stops, its results
 *                                  are deleted; its status document
 *   GET /jobs/{id}/results[?wait=false]
 *       the stored results of its visible chunks in chunk order: byte for
 *       byte the synchronous answer.  While the job runs, the chunks stored
 *       are written, then each as it is stored, to the last (the
 *       connection is suspended between them and looked at again by the
 *       ticker, jobs.c, holding no worker); ?wait=false writes those stored
 *       and ends.  A failed job answers its problem with its status; a
 *       dismissed one 404, as its results are gone.
 *
 * A malformed id is 400, an unknown one 404.  When the store cannot be
 * reached new jobs are answered 503 store-unavailable (with Retry-After);
 * synchronous requests do not touch it.  The work that grows with a body
 * (a submission's parse and its storing; a results request's job opened)
 * runs in the pool like a computation, and so do the status, the list and
 * the dismissal: no call of the store is made on the I/O thread.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/random.h>

#include "internal.h"

#define PAGE_DEFAULT 20 /* jobs in a page of GET /jobs */
#define PAGE_MAX 1000

/* ---- Prefer: respond-async ----------------------------------------------- */

/* Whether the preferences @a v (RFC 7240: preference *( "," preference ),
 * each a token, perhaps "=" a value, perhaps "; " parameters) name
 * respond-async, whatever its case. */
static int names_async(const char *v) {
  static const char TOKEN[] = "respond-async";
  const size_t n = sizeof TOKEN - 1;
  while (v && *v) {
    while (*v == ' ' || *v == '\t' || *v == ',')
      v++;
    if (!strncasecmp(v, TOKEN, n) && strchr(" \t=;,", v[n]))
      return 1;
    /* to the next preference: a comma outside a quoted string */
    int quoted = 0;
    for (; *v && (quoted || *v != ','); v++) {
      if (*v == '\\' && quoted && v[1])
        v++;
      else if (*v == '"')
        quoted = !quoted;
    }
  }
  return 0;
}

static enum MHD_Result prefer_header(void *cls, enum MHD_ValueKind kind,
                                     const char *key, const char *value) {
  (void)kind;
  if (!strcasecmp(key, "Prefer") && names_async(value))
    *(int *)cls = 1;
  return MHD_YES;
}

int srv__prefers_async(struct MHD_Connection *c) {
  int async = 0;
  MHD_get_connection_values(c, MHD_HEADER_KIND, prefer_header, &async);
  return async;
}

/* ---- what the store says, as the api writes it --------------------------- */

static api_job_info info_of(const store_job *sj) {
  api_job_info in = {
      sj->id,       sj->path,        store_status_name(sj->status),
      sj->created,  sj->started,     sj->updated,
      sj->finished, sj->items,       sj->items_done,
      sj->chunks,   sj->chunks_done, sj->message};
  return in;
}

/* The 503 of a store that failed (@a st NULL: not open). */
static void store_problem_of(store *st, api_response *out) {
  char detail[256];
  snprintf(detail, sizeof detail,
           "the job store is unavailable (%.120s); retry later, or send the "
           "request without Prefer: respond-async",
           st ? store_error(st) : "not open");
  api_problem(out, API_P_STORE_UNAVAILABLE, detail, NULL, NULL, 0);
}

/* ---- admission ----------------------------------------------------------- */

static int is_id(const char *s, size_t n) {
  if (n != STORE_ID_LEN)
    return 0;
  for (size_t i = 0; i < n; i++)
    if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
      return 0;
  return 1;
}

/* A whole number of the query's parameter @a name into *out (@a dflt when
 * absent), within [lo, hi]: 0, or -1 with the problem deferred. */
static int query_long(struct MHD_Connection *c, srv__req *r, const char *name,
                      long dflt, long lo, long hi, long *out) {
  const char *v = MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, name);
  char *end;
  *out = dflt;
  if (!v)
    return 0;
  long x = strtol(v, &end, 10);
  if (*v && !*end && *v != '-' && *v != '+' && x >= lo && x <= hi) {
    *out = x;
    return 0;
  }
  char detail[128];
  snprintf(detail, sizeof detail,
           "the parameter %s must be a whole number "
           "in [%ld, %ld]",
           name, lo, hi);
  srv__defer(r, API_P_BAD_REQUEST, detail, NULL);
  return -1;
}

/* The route of a job resource and its parameters (see the top). */
int srv__jobs_admit(struct srv_daemon *d, struct MHD_Connection *c, srv__req *r,
                    const char *url, const char *method) {
  if (strncmp(url, "/jobs", 5) || (url[5] && url[5] != '/'))
    return 0;
  r->ep = srv_metrics_jobs_row();
  const char *id = url[5] ? url + 6 : "";
  size_t n = strcspn(id, "/");
  const char *allow = "GET";
  if (!*id) {
    r->jobs = SRV__JOBS_LIST;
  } else if (!id[n] || (!strcmp(id + n, "/results"))) {
    r->jobs = id[n] ? SRV__JOBS_RESULTS : SRV__JOBS_ONE;
    allow = id[n] ? "GET" : "GET, DELETE";
    if (!is_id(id, n)) {
      srv__defer(r, API_P_BAD_REQUEST, "a job's id is 32 lowercase hex digits",
                 NULL);
      return 1;
    }
    memcpy(r->job_id, id, n);
    r->job_id[n] = 0;
  } else {
    srv__defer(r, API_P_NOT_FOUND, "no such resource; see /openapi.json", NULL);
    return 1;
  }
  if (!d->jobs) {
    srv__defer(r, API_P_NOT_FOUND, "this server keeps no jobs (--no-jobs)",
               NULL);
    return 1;
  }
  if (!strcmp(method, "OPTIONS")) {
    snprintf(r->preflight, sizeof r->preflight, "%s, OPTIONS", allow);
    return 1;
  }
  int delete = !strcmp(method, "DELETE");
  if ((strcmp(method, "GET") && strcmp(method, "HEAD") && !delete) ||
      (delete &&r->jobs != SRV__JOBS_ONE)) {
    snprintf(r->p_detail, sizeof r->p_detail, "this resource takes %s", allow);
    srv__defer(r, API_P_METHOD_NOT_ALLOWED, NULL, allow);
    return 1;
  }
  if (r->jobs == SRV__JOBS_LIST &&
      (query_long(c, r, "limit", PAGE_DEFAULT, 1, PAGE_MAX, &r->limit) ||
       query_long(c, r, "offset", 0, 0, 1L << 40, &r->offset)))
    return 1;
  if (r->jobs == SRV__JOBS_RESULTS) {
    const char *w =
        MHD_lookup_connection_value(c, MHD_GET_ARGUMENT_KIND, "wait");
    r->wait = !w || !strcmp(w, "true");
    if (w && !r->wait && strcmp(w, "false"))
      srv__defer(r, API_P_BAD_REQUEST,
                 "the parameter wait must be true or false", NULL);
  }
  return 1;
}

/* ---- the answers, made in the pool ---------------------------------------
 * Every call of the store is made on a worker, never on the I/O thread: a
 * PostgreSQL store is a round trip away, and one that stops answering
 * would stop every connection for as long as its timeouts last. */

static void list_into(srv__req *r, store *st, api_response *ar) {
  store_job *jobs = calloc((size_t)r->limit, sizeof *jobs);
  api_job_info *info = calloc((size_t)r->limit, sizeof *info);
  size_t n = 0;
  long total = 0;
  int rc = STORE_ERROR;
  if (!jobs || !info)
    api_problem(ar, API_P_OUT_OF_MEMORY, "out of memory", NULL, NULL, 0);
  else {
    SRV__TIMED(r->d, rc,
               store_list(st, r->offset, (size_t)r->limit, jobs, &n, &total));
    if (rc != 0)
      store_problem_of(st, ar);
  }
  if (rc == 0) {
    for (size_t i = 0; i < n; i++)
      info[i] = info_of(&jobs[i]);
    api_job_list_json(info, n, r->offset, r->limit, total, ar);
  }
  free(jobs);
  free(info);
}

/* The job's problem: what its failure stored. */
static void failure_into(srv__req *r, store *st, api_response *ar) {
  memset(ar, 0, sizeof *ar);
  int rc;
  SRV__TIMED(r->d, rc,
             store_problem(st, r->job_id, &ar->status, &ar->body, &ar->len));
  if (rc != 0) {
    free(ar->body);
    store_problem_of(st, ar);
  } else {
    ar->content_type = "application/problem+json";
    ar->held = ar->len;
  }
}

/* The answer to GET /jobs, GET or DELETE /jobs/{id}, into r->ar; for GET
 * /jobs/{id}/results of a job that has not failed, 1: its stream is to be
 * opened. */
static int answer(srv__req *r, store *st) {
  store_job sj;
  int rc;
  if (r->jobs == SRV__JOBS_LIST) {
    list_into(r, st, &r->ar);
    return 0;
  }
  if (!strcmp(r->method, "DELETE")) {
    SRV__TIMED(r->d, rc, store_dismiss(st, r->job_id, srv__wall()));
    if (rc == 0)
      srv__jobs_cancel(r->d->jobs, r->job_id);
  }
  SRV__TIMED(r->d, rc, store_get(st, r->job_id, &sj));
  if (rc == STORE_ERROR) {
    store_problem_of(st, &r->ar);
  } else if (rc == STORE_NONE ||
             (r->jobs == SRV__JOBS_RESULTS && sj.status == STORE_DISMISSED)) {
    api_problem(&r->ar, API_P_NOT_FOUND,
                rc == STORE_NONE ? "no such job (or it has expired)"
                                 : "the job was dismissed: its results are "
                                   "deleted",
                NULL, NULL, 0);
  } else if (r->jobs == SRV__JOBS_ONE) {
    api_job_info in = info_of(&sj);
    api_job_status_json(&in, &r->ar);
  } else if (sj.status == STORE_FAILED) {
    failure_into(r, st, &r->ar);
  } else {
    snprintf(r->job_path, sizeof r->job_path, "%s", sj.path);
    return 1;
  }
  return 0;
}

/* ---- the work done in the pool ------------------------------------------- */

/* Store the job of request @a r (its endpoint r->ep, its body r->buf), and
 * its status document into r->ar. */
static void submit_job(srv__req *r, store *st) {
  struct srv_daemon *d = r->d;
  api_limits lim = srv__job_limits(d);
  api_job *job = NULL;
  store_chunk *chunks = NULL;
  unsigned char bytes[STORE_ID_LEN / 2];
  store_job sj;
  memset(&sj, 0, sizeof sj);
  if (api_job_open_form(r->ep, (api_form)r->form, r->buf ? r->buf : "", r->len,
                        &lim, &job, &r->ar))
    return; /* its problem, as the synchronous request would be answered */
  size_t n = api_job_chunks(job);
  if (!(chunks = calloc(n, sizeof *chunks)) ||
      getrandom(bytes, sizeof bytes, 0) != (ssize_t)sizeof bytes) {
    api_problem(&r->ar, API_P_INTERNAL, "no memory or no randomness for a job",
                NULL, NULL, 0);
    goto done;
  }
  for (size_t k = 0; k < n; k++) {
    chunks[k].stage = api_job_stage(job, k);
    chunks[k].items = api_job_chunk_items(job, k);
  }
  for (size_t i = 0; i < sizeof bytes; i++)
    snprintf(sj.id + 2 * i, 3, "%02x", bytes[i]);
  srv__job_path(r->ep, (api_form)r->form, sj.path, sizeof sj.path);
  sj.status = STORE_ACCEPTED;
  sj.created = sj.updated = srv__wall();
  sj.chunks = (long)n;
  sj.items = api_job_items(job);
  int rc;
  SRV__TIMED(d, rc,
             store_submit(st, &sj, r->buf ? r->buf : "", r->len, chunks, n));
  if (rc != 0) {
    store_problem_of(st, &r->ar);
    goto done;
  }
  srv__jobs_wake(d->jobs);
  api_job_info in = info_of(&sj);
  api_job_status_json(&in, &r->ar);
  r->ar.status = 201;
  snprintf(r->location, sizeof r->location, "/jobs/%s", sj.id);
done:
  free(chunks);
  api_job_free(job);
}

struct srv__results {
  pthread_mutex_t mu;
  struct srv_daemon *d;
  struct MHD_Connection *c; /* NULL once the request has completed */
  srv__req *r;              /* likewise */
  api_job *job;
  char id[STORE_ID_LEN + 1];
  size_t k, n; /* the next chunk, and the chunks */
  int wait;
  char *buf; /* the chunk being written */
  size_t len, off;
  int refs; /* the response, the request, the reader's queue */
  /* what the reader last found (next_chunk's value), or FETCH_NONE when
   * nothing is asked and FETCH_ASKED while it reads (under mu) */
  int fetched;
  srv__results *next; /* in the reader's queue */
};

enum { FETCH_NONE = -10, FETCH_ASKED = -11 };

srv__results **srv__results_next(srv__results *res) { return &res->next; }

void srv__jobs_run(srv__req *r) {
  store *st = srv__jobs_store(r->d->jobs);
  if (!st) {
    store_problem_of(NULL, &r->ar);
    return;
  }
  if (r->async) {
    submit_job(r, st);
    return;
  }
  if (!answer(r, st))
    return;
  api_job *job = srv__jobs_open(r->d->jobs, r->job_id, r->job_path, &r->ar);
  if (!job) {
    if (!r->ar.status)
      api_problem(&r->ar, API_P_NOT_FOUND, "the job was dismissed", NULL, NULL,
                  0);
    return;
  }
  srv__results *res = calloc(1, sizeof *res);
  if (!res) {
    srv__jobs_release(r->d->jobs, job);
    api_problem(&r->ar, API_P_OUT_OF_MEMORY, "out of memory", NULL, NULL, 0);
    return;
  }
  pthread_mutex_init(&res->mu, NULL);
  res->d = r->d;
  res->job = job;
  res->n = api_job_chunks(job);
  res->wait = r->wait;
  res->refs = 1; /* the request's; the response takes another */
  res->fetched = FETCH_NONE;
  snprintf(res->id, sizeof res->id, "%s", r->job_id);
  r->res = res;
}

/* ---- the results' stream ------------------------------------------------- */

static void results_release(void *cls) {
  srv__results *res = cls;
  pthread_mutex_lock(&res->mu);
  int last = --res->refs == 0;
  pthread_mutex_unlock(&res->mu);
  if (!last)
    return;
  srv__jobs_release(res->d->jobs, res->job);
  free(res->buf);
  pthread_mutex_destroy(&res->mu);
  free(res);
}

void srv__results_resume(srv__results *res) {
  pthread_mutex_lock(&res->mu);
  if (res->c)
    MHD_resume_connection(res->c);
  pthread_mutex_unlock(&res->mu);
}

void srv__results_detach(srv__results *res) {
  srv__jobs_unwait(res->d->jobs, res);
  pthread_mutex_lock(&res->mu);
  res->c = NULL;
  res->r = NULL;
  pthread_mutex_unlock(&res->mu);
  results_release(res);
}

/* The next stored visible chunk into res->buf: 1; 0 when it is not stored
 * yet; -1 when the job will not give it (dismissed, failed, the store
 * failed); 2 at the end. */
static int next_chunk(srv__results *res, store *st) {
  for (;;) {
    while (res->k < res->n && !api_job_visible(res->job, res->k))
      res->k++;
    if (res->k == res->n)
      return 2;
    int rc;
    free(res->buf);
    res->buf = NULL;
    res->len = res->off = 0;
    SRV__TIMED(res->d, rc,
               store_result(st, res->id, (long)res->k, &res->buf, &res->len));
    if (rc == 0) {
      res->k++;
      return 1;
    }
    if (rc == STORE_ERROR)
      return -1;
    store_job sj;
    SRV__TIMED(res->d, rc, store_get(st, res->id, &sj));
    if (rc != 0 || (sj.status != STORE_ACCEPTED && sj.status != STORE_RUNNING &&
                    sj.status != STORE_SUCCESSFUL))
      return -1;
    if (sj.status != STORE_SUCCESSFUL)
      return 0;
    /* stored between the two calls: read again */
  }
}

void srv__results_fetch(srv__results *res) {
  struct srv_daemon *d = res->d;
  store *st = srv__jobs_store(d->jobs);
  int rc = st && !atomic_load(&d->draining) ? next_chunk(res, st) : -1;
  pthread_mutex_lock(&res->mu);
  res->fetched = rc;
  if (res->c)
    MHD_resume_connection(res->c);
  pthread_mutex_unlock(&res->mu);
  results_release(res); /* the queue's reference */
}

/* The stream's bytes: what the reader put in res->buf.  When it is spent
 * the connection is suspended and the reader asked for the next chunk
 * (resumed when it is read), or, when that chunk is not stored yet, the
 * ticker asked to resume it to ask again. */
static ssize_t results_read(void *cls, uint64_t pos, char *buf, size_t max) {
  srv__results *res = cls;
  struct srv_daemon *d = res->d;
  (void)pos;
  while (res->off == res->len) {
    pthread_mutex_lock(&res->mu);
    int rc = res->fetched;
    res->fetched = rc == FETCH_NONE ? FETCH_ASKED : FETCH_NONE;
    if (rc == FETCH_NONE)
      res->refs++; /* the reader's queue holds it */
    pthread_mutex_unlock(&res->mu);
    if (rc == FETCH_NONE) {
      MHD_suspend_connection(res->c);
      srv__jobs_fetch(d->jobs, res);
      return 0;
    }
    if (rc < 0 || atomic_load(&d->draining))
      return MHD_CONTENT_READER_END_WITH_ERROR; /* the answer is cut */
    if (rc == 2 || (rc == 0 && !res->wait))
      return MHD_CONTENT_READER_END_OF_STREAM;
    if (rc == 0) {
      /* the ticker resumes the connection to ask again */
      MHD_suspend_connection(res->c);
      srv__jobs_wait(d->jobs, res);
      return 0;
    }
  }
  size_t k = res->len - res->off < max ? res->len - res->off : max;
  memcpy(buf, res->buf + res->off, k);
  res->off += k;
  if (res->r)
    res->r->bytes += k;
  return (ssize_t)k;
}

/* Back on the I/O thread: the results' stream starts. */
enum MHD_Result srv__jobs_resumed(struct srv_daemon *d,
                                  struct MHD_Connection *c, srv__req *r) {
  srv__results *res = r->res;
  (void)d;
  if (!res)
    return srv__send_api(c, r, &r->ar, NULL);
  res->c = c;
  res->r = r;
  res->refs++;
  struct MHD_Response *resp = MHD_create_response_from_callback(
      MHD_SIZE_UNKNOWN, SRV__STREAM_CHUNK, results_read, res, results_release);
  if (!resp) {
    results_release(res); /* the response's reference */
    return MHD_NO;
  }
  MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE,
                          api_job_content_type(res->job));
  srv__common_headers(r, resp);
  enum MHD_Result ok = MHD_queue_response(c, MHD_HTTP_OK, resp);
  MHD_destroy_response(resp);
  r->status = MHD_HTTP_OK;
  r->done = 1;
  return ok;
}
