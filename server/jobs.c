/*
 * jobs.c: the engine of jobs: the store, the runners that compute chunks,
 * and the ticker.
 *
 * The store (store.h) holds every job, its chunks and their results; this
 * replica is one of those that compute them.  A runner (--job-workers
 * threads) claims a chunk of any job in the store under a lease of
 * --job-lease seconds, in its owner's name (the host, the process and its
 * start, so that a restarted daemon is another owner), computes it with the api
 * (api_job_run, reading the results of earlier stages from the store), and
 * stores its result, or fails the job with the chunk's problem.  With
 * nothing to claim it sleeps until a job is submitted here or IDLE_POLL
 * passes (jobs of other replicas, leases that lapsed).  A daemon killed
 * and started again finds the jobs it had accepted or was running in the
 * store: their chunks not stored are claimable once their leases lapse.
 *
 * The ticker, every TICK_MS: renews the leases of the chunks computing
 * (every third of the lease, so that two renewals may fail), stops a
 * chunk whose job is no longer the store's to compute (dismissed or failed,
 * here or by another replica; the lease taken by another), resumes the results
 * streams that wait for their next chunk (jobs_http.c), and expires finished
 * jobs older than --job-ttl (every SWEEP_EVERY).  A DELETE on this replica
 * stops its chunks at once (srv__jobs_cancel).
 *
 * The reader reads the chunks that results streams send, one at a time in
 * the order they are asked: the I/O thread never calls the store, which
 * may be a round trip away or, for a while, not answer at all.
 *
 * An opened job (api_job_open of its stored body) is kept in a small cache
 * of the CACHE last used, shared by the runners and the results streams,
 * so that the body of a batch of ten thousand chunks is parsed once, not
 * once a chunk.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>

#include "internal.h"

#define IDLE_POLL 0.25   /* a runner with nothing to claim looks again */
#define TICK_MS 50       /* the ticker's period */
#define CHECK_EVERY 0.05 /* whether a computing chunk's job still runs */
#define SWEEP_EVERY 60.0 /* expiry of finished jobs */
#define REOPEN_EVERY 5.0 /* a store that could not be opened, again */
#define COUNTS_EVERY 1.0 /* the store's counts for the metrics */
#define CACHE 8          /* jobs kept opened */

typedef struct runner {
  srv__jobs *js;
  pthread_t th;
  int started;
  /* the chunk being computed (under js->mu) */
  int busy;
  char id[STORE_ID_LEN + 1];
  long chunk;
  double renewed, checked;
  atomic_int cancel;
} runner;

typedef struct cached {
  char id[STORE_ID_LEN + 1];
  api_job *job; /* NULL: a free slot */
  int refs;
  int stale; /* dismissed: freed once no one holds it */
  unsigned long used;
} cached;

struct srv__jobs {
  struct srv_daemon *d;
  pthread_mutex_t mu;
  pthread_cond_t wake;
  store *st;
  double reopen_at;
  char owner[160];
  int stop;    /* runners */
  int stop_tk; /* the ticker */
  runner *run;
  unsigned n_run;
  pthread_t ticker;
  int ticker_started;
  cached cache[CACHE];
  unsigned long clock;
  srv__results **waiting; /* results streams to resume */
  size_t n_waiting, cap_waiting;
  /* results streams whose next chunk is to be read, first to last */
  srv__results *fetch_head, *fetch_tail;
  pthread_cond_t fetch_cv;
  pthread_t reader;
  int reader_started;
  double counts_at;
  char note[1024]; /* what opening the store at the start had to say */
};

api_limits srv__job_limits(const struct srv_daemon *d) {
  api_limits lim = d->cfg.lim;
  lim.max_body = d->cfg.max_job_body;
  lim.max_batch_items = d->cfg.max_job_items;
  return lim;
}

double srv__wall(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- the store ----------------------------------------------------------- */

/* The directory of a "sqlite:PATH" store, made when it is not there (the
 * default one, under --state-dir, is the daemon's to make). */
static void make_parent(const char *uri) {
  if (strncmp(uri, "sqlite:", 7) != 0)
    return;
  char dir[512];
  snprintf(dir, sizeof dir, "%s", uri + 7);
  char *slash = strrchr(dir, '/');
  if (!slash || slash == dir)
    return;
  *slash = 0;
  if (mkdir(dir, 0750) != 0 && errno != EEXIST)
    fprintf(stderr, "stickslipd: cannot make %s: %s\n", dir, strerror(errno));
}

/* Open the store (under js->mu, or before any thread shares js); what it
 * has to say goes to the log, or into js->note when @a later. */
static void open_store(srv__jobs *js, int later) {
  char why[256] = "", note[sizeof js->note];
  make_parent(js->d->cfg.job_store);
  if (store_open(js->d->cfg.job_store, &js->st, why, sizeof why) != 0) {
    js->st = NULL;
    js->reopen_at = srv__now() + REOPEN_EVERY;
    snprintf(
        note, sizeof note,
        "stickslipd: the job store %.512s cannot be opened (%.256s): jobs are "
        "answered 503 until it can; synchronous requests are served\n",
        js->d->cfg.job_store, why);
  } else {
    snprintf(note, sizeof note, "stickslipd: job store %.512s (%s)\n",
             js->d->cfg.job_store, store_kind(js->st));
  }
  if (later)
    memcpy(js->note, note, sizeof note);
  else
    fputs(note, stderr);
}

void srv__jobs_announce(srv__jobs *js) {
  if (js && js->note[0])
    fputs(js->note, stderr);
}

store *srv__jobs_store(srv__jobs *js) {
  pthread_mutex_lock(&js->mu);
  if (!js->st && js->d->cfg.job_store[0] && srv__now() >= js->reopen_at)
    open_store(js, 0);
  store *st = js->st;
  pthread_mutex_unlock(&js->mu);
  return st;
}

void srv__jobs_metrics(srv__jobs *js) {
  long by[5] = {0, 0, 0, 0, 0}, pending = 0;
  pthread_mutex_lock(&js->mu);
  int due = srv__now() >= js->counts_at;
  if (due)
    js->counts_at = srv__now() + COUNTS_EVERY;
  pthread_mutex_unlock(&js->mu);
  if (!due)
    return;
  store *st = srv__jobs_store(js);
  int rc = STORE_ERROR;
  if (st)
    SRV__TIMED(js->d, rc, store_counts(st, by, &pending));
  srv_metrics_jobs(js->d->metrics, rc == 0, by, pending);
}

/* ---- the cache of opened jobs -------------------------------------------- */

/* The slot to fill (under js->mu): a free one, else the least used that no
 * one holds (freed), else NULL. */
static cached *cache_slot(srv__jobs *js) {
  cached *best = NULL;
  for (int i = 0; i < CACHE; i++) {
    cached *e = &js->cache[i];
    if (!e->job)
      return e;
    if (e->refs == 0 && (!best || e->used < best->used))
      best = e;
  }
  if (best) {
    api_job_free(best->job);
    best->job = NULL;
  }
  return best;
}

/* The NDJSON form of an endpoint that answers JSON by default is kept in
 * the job's path as the query OGC API - Common names a format with. */
static const char NDJSON_QUERY[] = "?f=ndjson";

void srv__job_path(size_t ep, api_form form, char *path, size_t n) {
  snprintf(path, n, "%s%s", api_endpoint_at(ep)->path,
           form == API_FORM_NDJSON ? NDJSON_QUERY : "");
}

int srv__job_route(const char *path, size_t *ep, api_form *form) {
  char bare[32];
  size_t n = strcspn(path, "?");
  *form = API_FORM_DEFAULT;
  if (path[n]) {
    if (strcmp(path + n, NDJSON_QUERY) != 0)
      return -1;
    *form = API_FORM_NDJSON;
  }
  snprintf(bare, sizeof bare, "%.*s", (int)n, path);
  return api_route("POST", bare, ep) == 200 ? 0 : -1;
}

api_job *srv__jobs_open(srv__jobs *js, const char *id, const char *path,
                        api_response *out) {
  memset(out, 0, sizeof *out);
  pthread_mutex_lock(&js->mu);
  for (int i = 0; i < CACHE; i++) {
    cached *e = &js->cache[i];
    if (e->job && !e->stale && !strcmp(e->id, id)) {
      e->refs++;
      e->used = ++js->clock;
      pthread_mutex_unlock(&js->mu);
      return e->job;
    }
  }
  pthread_mutex_unlock(&js->mu);
  store *st = srv__jobs_store(js);
  char *body = NULL;
  size_t len = 0;
  size_t ep;
  int rc = STORE_ERROR;
  if (st)
    SRV__TIMED(js->d, rc, store_body(st, id, &body, &len));
  if (rc == STORE_ERROR) {
    api_problem(out, API_P_STORE_UNAVAILABLE, "the job store failed", NULL,
                NULL, 0);
    return NULL;
  }
  if (rc == STORE_NONE)
    return NULL;
  api_job *job = NULL;
  api_limits lim = srv__job_limits(js->d);
  api_form form = API_FORM_DEFAULT;
  if (srv__job_route(path, &ep, &form) != 0)
    api_problem(out, API_P_NOT_FOUND, "the job's endpoint is not served here",
                NULL, NULL, 0);
  else
    api_job_open_form(ep, form, body, len, &lim, &job, out);
  free(body);
  if (!job)
    return NULL;
  pthread_mutex_lock(&js->mu);
  cached *e = cache_slot(js);
  if (e) {
    snprintf(e->id, sizeof e->id, "%s", id);
    e->job = job;
    e->refs = 1;
    e->stale = 0;
    e->used = ++js->clock;
  }
  pthread_mutex_unlock(&js->mu);
  return job; /* not cached (every slot held): srv__jobs_release frees it */
}

void srv__jobs_release(srv__jobs *js, api_job *j) {
  int cached_here = 0;
  pthread_mutex_lock(&js->mu);
  for (int i = 0; i < CACHE; i++) {
    cached *e = &js->cache[i];
    if (e->job == j) {
      cached_here = 1;
      if (--e->refs == 0 && e->stale) {
        api_job_free(e->job);
        e->job = NULL;
      }
    }
  }
  pthread_mutex_unlock(&js->mu);
  if (!cached_here)
    api_job_free(j);
}

/* ---- local cancellation and waiting streams ------------------------------ */

void srv__jobs_cancel(srv__jobs *js, const char *id) {
  pthread_mutex_lock(&js->mu);
  for (unsigned i = 0; i < js->n_run; i++)
    if (js->run[i].busy && !strcmp(js->run[i].id, id))
      atomic_store(&js->run[i].cancel, 1);
  for (int i = 0; i < CACHE; i++) {
    cached *e = &js->cache[i];
    if (e->job && !strcmp(e->id, id)) {
      e->stale = 1;
      if (e->refs == 0) {
        api_job_free(e->job);
        e->job = NULL;
      }
    }
  }
  pthread_mutex_unlock(&js->mu);
}

void srv__jobs_wake(srv__jobs *js) {
  pthread_mutex_lock(&js->mu);
  pthread_cond_broadcast(&js->wake);
  pthread_mutex_unlock(&js->mu);
}

void srv__jobs_wait(srv__jobs *js, srv__results *res) {
  pthread_mutex_lock(&js->mu);
  if (js->n_waiting == js->cap_waiting) {
    size_t cap = js->cap_waiting ? 2 * js->cap_waiting : 16;
    srv__results **w = realloc(js->waiting, cap * sizeof *w);
    if (w) {
      js->waiting = w;
      js->cap_waiting = cap;
    }
  }
  if (js->n_waiting < js->cap_waiting)
    js->waiting[js->n_waiting++] = res;
  else
    srv__results_resume(res); /* out of memory: tried again at once */
  pthread_mutex_unlock(&js->mu);
}

void srv__jobs_unwait(srv__jobs *js, srv__results *res) {
  pthread_mutex_lock(&js->mu);
  for (size_t i = 0; i < js->n_waiting; i++)
    if (js->waiting[i] == res)
      js->waiting[i--] = js->waiting[--js->n_waiting];
  pthread_mutex_unlock(&js->mu);
}

void srv__jobs_fetch(srv__jobs *js, srv__results *res) {
  if (!js->reader_started) { /* no thread could be made: read here */
    srv__results_fetch(res);
    return;
  }
  pthread_mutex_lock(&js->mu);
  *srv__results_next(res) = NULL;
  if (js->fetch_tail)
    *srv__results_next(js->fetch_tail) = res;
  else
    js->fetch_head = res;
  js->fetch_tail = res;
  pthread_cond_signal(&js->fetch_cv);
  pthread_mutex_unlock(&js->mu);
}

/* Until the ticker stops, and then until its queue is empty (every stream
 * asked is answered, if only by its end). */
static void *reader_main(void *arg) {
  srv__jobs *js = arg;
  pthread_mutex_lock(&js->mu);
  for (;;) {
    srv__results *res = js->fetch_head;
    if (!res) {
      if (js->stop_tk)
        break;
      pthread_cond_wait(&js->fetch_cv, &js->mu);
      continue;
    }
    js->fetch_head = *srv__results_next(res);
    if (!js->fetch_head)
      js->fetch_tail = NULL;
    pthread_mutex_unlock(&js->mu);
    srv__results_fetch(res);
    pthread_mutex_lock(&js->mu);
  }
  pthread_mutex_unlock(&js->mu);
  return NULL;
}

/* ---- runners ------------------------------------------------------------- */

static int runner_cancelled(void *cls) {
  return atomic_load(&((runner *)cls)->cancel);
}

/* A chunk computes on its runner's thread alone: --job-workers is the
 * parallelism of jobs. */
static unsigned one_thread(void *cls, unsigned want) {
  (void)cls;
  (void)want;
  return 1;
}

typedef struct inputs_cls {
  srv__jobs *js;
  store *st;
  const char *id;
} inputs_cls;

static int read_input(void *cls, size_t k, char **buf, size_t *len) {
  inputs_cls *in = cls;
  int rc;
  SRV__TIMED(in->js->d, rc, store_result(in->st, in->id, (long)k, buf, len));
  return rc == 0 ? 0 : -1;
}

/* Fail job @a id with the problem @a out (its detail is the job's
 * message). */
static void fail_job(srv__jobs *js, store *st, const char *id,
                     const api_response *out) {
  char message[256] = "";
  json_t *p = out->body ? json_loadb(out->body, out->len, 0, NULL) : NULL;
  const char *detail = p ? json_string_value(json_object_get(p, "detail")) : 0;
  snprintf(message, sizeof message, "%s", detail ? detail : "failed");
  json_decref(p);
  int rc;
  SRV__TIMED(js->d, rc,
             store_fail(st, id, message, out->status,
                        out->body ? out->body : "", out->len, srv__wall()));
  if (rc == STORE_ERROR)
    fprintf(stderr, "stickslipd: job %s: its failure not stored: %s\n", id,
            store_error(st));
}

/* The limits of chunk @a k of a job that started at @a started: the
 * job's time limit less what it has used. */
static api_limits chunk_limits(const srv__jobs *js, double started) {
  api_limits lim = srv__job_limits(js->d);
  double used = started > 0 ? srv__wall() - started : 0;
  lim.max_seconds = js->d->cfg.job_max_seconds - (used > 0 ? used : 0);
  return lim;
}

/* Compute chunk @a k of job @a id and store its result (or its problem). */
static void run_chunk(runner *ru, store *st, const char *id, long k) {
  srv__jobs *js = ru->js;
  store_job sj;
  api_response out;
  int rc;
  SRV__TIMED(js->d, rc, store_get(st, id, &sj));
  if (rc != 0)
    return; /* gone, or the store failed: the lease lapses */
  api_job *job = srv__jobs_open(js, id, sj.path, &out);
  if (!job) {
    if (out.status && out.status != 503)
      fail_job(js, st, id, &out);
    api_response_free(&out);
    return;
  }
  api_limits lim = chunk_limits(js, sj.started);
  size_t ep = api_endpoint_count(); /* its endpoint, for the metrics */
  api_form form;
  srv__job_route(sj.path, &ep, &form);
  pthread_mutex_lock(&js->mu);
  ru->busy = 1;
  snprintf(ru->id, sizeof ru->id, "%s", id);
  ru->chunk = k;
  ru->renewed = ru->checked = srv__now();
  atomic_store(&ru->cancel, js->stop);
  pthread_mutex_unlock(&js->mu);
  inputs_cls icls = {js, st, id};
  api_job_inputs in = {read_input, &icls};
  api_server_info info = {srv__now() - js->d->started,
                          0,
                          js->d->transport,
                          NULL,
                          NULL,
                          runner_cancelled,
                          ru,
                          0,
                          one_thread,
                          NULL};
  if (lim.max_seconds <= 0)
    api_problem(&out, API_P_LIMIT, "the job is over its time limit", NULL,
                "job_max_seconds", js->d->cfg.job_max_seconds);
  else
    api_job_run(job, (size_t)k, &in, &lim, &info, &out);
  pthread_mutex_lock(&js->mu);
  ru->busy = 0;
  int cancelled = atomic_load(&ru->cancel);
  pthread_mutex_unlock(&js->mu);
  if (cancelled) {
    /* dismissed, or this replica stops: nothing is stored */
  } else if (out.status == 200) {
    SRV__TIMED(
        js->d, rc,
        store_complete(st, js->owner, id, k, out.body, out.len, srv__wall()));
    if (rc == 0)
      srv_metrics_job_chunk(js->d->metrics, ep,
                            api_job_chunk_items(job, (size_t)k));
    else if (rc == STORE_ERROR)
      fprintf(stderr, "stickslipd: job %s chunk %ld not stored: %s\n", id, k,
              store_error(st));
  } else {
    fail_job(js, st, id, &out);
  }
  api_response_free(&out);
  srv__jobs_release(js, job);
}

/* Sleep until a job is submitted here, the runners stop, or @a seconds
 * pass. */
static void idle(srv__jobs *js, double seconds) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  long ns = ts.tv_nsec + (long)(seconds * 1e9);
  ts.tv_sec += ns / 1000000000L;
  ts.tv_nsec = ns % 1000000000L;
  pthread_mutex_lock(&js->mu);
  if (!js->stop)
    pthread_cond_timedwait(&js->wake, &js->mu, &ts);
  pthread_mutex_unlock(&js->mu);
}

static int stopping(srv__jobs *js) {
  pthread_mutex_lock(&js->mu);
  int stop = js->stop;
  pthread_mutex_unlock(&js->mu);
  return stop;
}

static void *runner_main(void *arg) {
  runner *ru = arg;
  srv__jobs *js = ru->js;
  while (!stopping(js)) {
    store *st = srv__jobs_store(js);
    char id[STORE_ID_LEN + 1];
    long k;
    int rc = STORE_ERROR;
    if (st)
      SRV__TIMED(js->d, rc,
                 store_claim(st, js->owner, srv__wall(), js->d->cfg.job_lease,
                             id, &k));
    if (rc == 0)
      run_chunk(ru, st, id, k);
    else
      idle(js, IDLE_POLL);
  }
  return NULL;
}

/* ---- the ticker ---------------------------------------------------------- */

/* A computing chunk whose job the store no longer has running, or whose
 * lease could not be renewed, stops. */
static void watch_runner(srv__jobs *js, store *st, runner *ru, double now) {
  char id[STORE_ID_LEN + 1];
  long k;
  int renew, check, rc;
  pthread_mutex_lock(&js->mu);
  renew = ru->busy && now - ru->renewed >= js->d->cfg.job_lease / 3;
  check = ru->busy && now - ru->checked >= CHECK_EVERY;
  memcpy(id, ru->id, sizeof id);
  k = ru->chunk;
  pthread_mutex_unlock(&js->mu);
  int gone = 0;
  if (renew) {
    SRV__TIMED(
        js->d, rc,
        store_renew(st, js->owner, id, k, srv__wall() + js->d->cfg.job_lease));
    gone = rc == STORE_NONE;
    pthread_mutex_lock(&js->mu);
    ru->renewed = now;
    pthread_mutex_unlock(&js->mu);
  }
  if (check && !gone) {
    store_job sj;
    SRV__TIMED(js->d, rc, store_get(st, id, &sj));
    gone = rc == STORE_NONE || (rc == 0 && sj.status != STORE_ACCEPTED &&
                                sj.status != STORE_RUNNING);
    pthread_mutex_lock(&js->mu);
    ru->checked = now;
    pthread_mutex_unlock(&js->mu);
  }
  pthread_mutex_lock(&js->mu);
  if (gone && ru->busy && !strcmp(ru->id, id) && ru->chunk == k)
    atomic_store(&ru->cancel, 1);
  pthread_mutex_unlock(&js->mu);
}

static void resume_waiting(srv__jobs *js) {
  pthread_mutex_lock(&js->mu);
  for (size_t i = 0; i < js->n_waiting; i++)
    srv__results_resume(js->waiting[i]);
  js->n_waiting = 0;
  pthread_mutex_unlock(&js->mu);
}

static void *ticker_main(void *arg) {
  srv__jobs *js = arg;
  double sweep_at = 0;
  struct timespec tick = {0, TICK_MS * 1000000L};
  for (;;) {
    pthread_mutex_lock(&js->mu);
    int stop = js->stop_tk;
    pthread_mutex_unlock(&js->mu);
    if (stop)
      break;
    resume_waiting(js);
    store *st = srv__jobs_store(js);
    double now = srv__now();
    for (unsigned i = 0; st && i < js->n_run; i++)
      watch_runner(js, st, &js->run[i], now);
    if (st && now >= sweep_at) {
      long n = 0;
      int rc;
      sweep_at = now + SWEEP_EVERY;
      SRV__TIMED(js->d, rc,
                 store_expire(st, srv__wall() - js->d->cfg.job_ttl, &n));
      if (rc == 0 && n > 0)
        fprintf(stderr, "stickslipd: %ld finished jobs expired\n", n);
    }
    nanosleep(&tick, NULL);
  }
  return NULL;
}

/* ---- start and stop ------------------------------------------------------ */

srv__jobs *srv__jobs_start(struct srv_daemon *d) {
  srv__jobs *js = calloc(1, sizeof *js);
  if (!js)
    return NULL;
  js->d = d;
  pthread_mutex_init(&js->mu, NULL);
  pthread_cond_init(&js->wake, NULL);
  pthread_cond_init(&js->fetch_cv, NULL);
  char host[64] = "?";
  gethostname(host, sizeof host - 1);
  snprintf(js->owner, sizeof js->owner, "%s:%ld:%.0f", host, (long)getpid(),
           srv__wall());
  if (d->cfg.job_store[0])
    open_store(js, 1);
  js->n_run = d->cfg.job_workers;
  if (js->n_run && !(js->run = calloc(js->n_run, sizeof *js->run))) {
    srv__jobs_free(js);
    return NULL;
  }
  for (unsigned i = 0; i < js->n_run; i++) {
    js->run[i].js = js;
    js->run[i].started =
        pthread_create(&js->run[i].th, NULL, runner_main, &js->run[i]) == 0;
  }
  js->ticker_started = pthread_create(&js->ticker, NULL, ticker_main, js) == 0;
  js->reader_started = pthread_create(&js->reader, NULL, reader_main, js) == 0;
  return js;
}

void srv__jobs_stop(srv__jobs *js) {
  if (!js)
    return;
  pthread_mutex_lock(&js->mu);
  js->stop = 1;
  for (unsigned i = 0; i < js->n_run; i++)
    atomic_store(&js->run[i].cancel, 1);
  pthread_cond_broadcast(&js->wake);
  pthread_mutex_unlock(&js->mu);
  for (unsigned i = 0; i < js->n_run; i++)
    if (js->run[i].started) {
      pthread_join(js->run[i].th, NULL);
      js->run[i].started = 0;
    }
}

void srv__jobs_free(srv__jobs *js) {
  if (!js)
    return;
  srv__jobs_stop(js);
  pthread_mutex_lock(&js->mu);
  js->stop_tk = 1;
  pthread_cond_signal(&js->fetch_cv);
  pthread_mutex_unlock(&js->mu);
  if (js->ticker_started)
    pthread_join(js->ticker, NULL);
  if (js->reader_started)
    pthread_join(js->reader, NULL);
  resume_waiting(js);
  for (int i = 0; i < CACHE; i++)
    api_job_free(js->cache[i].job);
  store_close(js->st);
  free(js->waiting);
  free(js->run);
  pthread_cond_destroy(&js->wake);
  pthread_cond_destroy(&js->fetch_cv);
  pthread_mutex_destroy(&js->mu);
  free(js);
}
