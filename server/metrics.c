/*
 * metrics.c: counters and latency histograms in the Prometheus text format.
 * The endpoint labels are the api's endpoint table, "jobs" for the job
 * resources and "other"; requests are counted by their exact status; the
 * jobs by status and the chunks pending are the store's (shared by
 * replicas), the chunks computed this replica's; the process metrics are
 * those Prometheus's client libraries export (CPU, memory, descriptors,
 * start time).
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "server.h"

/* From /health's tenth of a millisecond to the minute of a search, a map
 * or a certificate. */
static const double BOUNDS[SRV_BUCKETS] = {
    0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05,
    0.1,    0.25,    0.5,    1.0,   2.5,    5.0,   10.0, 30.0,  60.0};

#define N_STATUS 500 /* statuses 100..599, by status - 100 */

typedef struct ep_metrics {
  atomic_ulong status[N_STATUS];
  atomic_ulong batch_status[N_STATUS]; /* items of batches on this path */
  atomic_ulong job_items; /* items of jobs' chunks on this path stored here */
  atomic_ulong latency_ns_sum;
  atomic_ulong latency_bucket[SRV_BUCKETS + 1];
  atomic_uint queued; /* its requests waiting for a worker (the pool's) */
} ep_metrics;

struct srv_metrics {
  size_t n; /* endpoints + "other" + "jobs" */
  ep_metrics *ep;
  atomic_long in_flight;
  atomic_ulong rejected_busy, cancelled, slow, rejected_memory;
  atomic_long held, held_peak;
  atomic_uint workers, busy, waiting, clients; /* the pool's load */
  double start_time;                           /* since the epoch */
  /* jobs: chunks computed here, the store's latency, the store's counts */
  atomic_ulong job_chunks;
  atomic_ulong store_ns_sum, store_bucket[SRV_BUCKETS + 1];
  pthread_mutex_t jobs_mu;
  int jobs_known;
  long jobs_by_status[5], jobs_pending;
  char build[160]; /* the labels of stickslip_build_info */
};

srv_metrics *srv_metrics_new(void) {
  srv_metrics *m = calloc(1, sizeof *m);
  if (!m)
    return NULL;
  m->n = api_endpoint_count() + 2;
  if (!(m->ep = calloc(m->n, sizeof *m->ep))) {
    free(m);
    return NULL;
  }
  pthread_mutex_init(&m->jobs_mu, NULL);
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  m->start_time = (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
  return m;
}

void srv_metrics_build(srv_metrics *m, const char *version,
                       const char *transport) {
  snprintf(m->build, sizeof m->build, "version=\"%.40s\",transport=\"%.60s\"",
           version, transport ? transport : "");
}

void srv_metrics_free(srv_metrics *m) {
  if (m) {
    free(m->ep);
    pthread_mutex_destroy(&m->jobs_mu);
  }
  free(m);
}

/* The rows: the endpoints, "other" (api_endpoint_count(), which is also
 * what a batch's item of no endpoint and a request not routed have), and
 * "jobs" last. */
size_t srv_metrics_jobs_row(void) { return api_endpoint_count() + 1; }

static const char *label(const srv_metrics *m, size_t i) {
  return i + 2 < m->n   ? api_endpoint_at(i)->label
         : i + 1 < m->n ? "other"
                        : "jobs";
}

/* The row of @a ep: "other" for anything that is no row. */
static size_t row(const srv_metrics *m, size_t ep) {
  return ep < m->n ? ep : m->n - 2;
}

void srv_metrics_observe(srv_metrics *m, size_t ep, int status,
                         double seconds) {
  ep = row(m, ep);
  if (status < 100 || status > 599)
    status = 500;
  ep_metrics *e = &m->ep[ep];
  atomic_fetch_add(&e->status[status - 100], 1);
  atomic_fetch_add(&e->latency_ns_sum, (unsigned long)(seconds * 1e9));
  int b = 0;
  while (b < SRV_BUCKETS && seconds > BOUNDS[b])
    b++;
  atomic_fetch_add(&e->latency_bucket[b], 1);
}

void srv_metrics_batch_item(srv_metrics *m, size_t ep, int status) {
  ep = row(m, ep);
  if (status < 100 || status > 599)
    status = 500;
  atomic_fetch_add(&m->ep[ep].batch_status[status - 100], 1);
}

void srv_metrics_pool(srv_metrics *m, srv_pool *p) {
  srv_pool_load_t load;
  unsigned *by = calloc(m->n, sizeof *by);
  srv_pool_load(p, &load, by, by ? m->n : 0);
  atomic_store(&m->workers, load.workers);
  atomic_store(&m->busy, load.running);
  atomic_store(&m->waiting, load.waiting);
  atomic_store(&m->clients, load.clients);
  for (size_t e = 0; by && e < m->n; e++)
    atomic_store(&m->ep[e].queued, by[e]);
  free(by);
}

void srv_metrics_job_chunk(srv_metrics *m, size_t ep, long items) {
  atomic_fetch_add(&m->job_chunks, 1);
  if (items > 0)
    atomic_fetch_add(&m->ep[row(m, ep)].job_items, (unsigned long)items);
}

void srv_metrics_store(srv_metrics *m, double seconds) {
  int b = 0;
  while (b < SRV_BUCKETS && seconds > BOUNDS[b])
    b++;
  atomic_fetch_add(&m->store_bucket[b], 1);
  atomic_fetch_add(&m->store_ns_sum, (unsigned long)(seconds * 1e9));
}

void srv_metrics_jobs(srv_metrics *m, int known, const long by_status[5],
                      long pending) {
  pthread_mutex_lock(&m->jobs_mu);
  m->jobs_known = known;
  if (known) {
    memcpy(m->jobs_by_status, by_status, sizeof m->jobs_by_status);
    m->jobs_pending = pending;
  }
  pthread_mutex_unlock(&m->jobs_mu);
}

void srv_metrics_busy(srv_metrics *m) {
  atomic_fetch_add(&m->rejected_busy, 1);
}

void srv_metrics_cancelled(srv_metrics *m) {
  atomic_fetch_add(&m->cancelled, 1);
}

void srv_metrics_slow(srv_metrics *m) { atomic_fetch_add(&m->slow, 1); }

void srv_metrics_over_budget(srv_metrics *m) {
  atomic_fetch_add(&m->rejected_memory, 1);
}

long srv_metrics_held(srv_metrics *m, long delta) {
  long now = atomic_fetch_add(&m->held, delta) + delta;
  long peak = atomic_load(&m->held_peak);
  while (now > peak && !atomic_compare_exchange_weak(&m->held_peak, &peak, now))
    ;
  return now;
}

long srv_metrics_in_flight(srv_metrics *m, int delta) {
  return atomic_fetch_add(&m->in_flight, delta) + delta;
}

typedef struct sbuf {
  char *p;
  size_t len, cap;
} sbuf;

static void put(sbuf *s, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void put(sbuf *s, const char *fmt, ...) {
  va_list ap;
  if (!s->p)
    return;
  for (;;) {
    va_start(ap, fmt);
    int n = vsnprintf(s->p + s->len, s->cap - s->len, fmt, ap);
    va_end(ap);
    if (n < 0)
      return;
    if (s->len + (size_t)n < s->cap) {
      s->len += (size_t)n;
      return;
    }
    char *q = realloc(s->p, 2 * s->cap + (size_t)n);
    if (!q) {
      free(s->p);
      s->p = NULL;
      return;
    }
    s->p = q;
    s->cap = 2 * s->cap + (size_t)n;
  }
}

/* A histogram @a metric of the BOUNDS, its series labelled @a labels
 * (with a trailing comma, or ""). */
static void histogram(sbuf *s, const char *metric, const char *labels,
                      atomic_ulong *bucket, atomic_ulong *ns_sum) {
  unsigned long cum = 0;
  for (int b = 0; b < SRV_BUCKETS; b++) {
    cum += atomic_load(&bucket[b]);
    put(s, "%s_bucket{%sle=\"%g\"} %lu\n", metric, labels, BOUNDS[b], cum);
  }
  cum += atomic_load(&bucket[SRV_BUCKETS]);
  put(s, "%s_bucket{%sle=\"+Inf\"} %lu\n", metric, labels, cum);
  size_t n = strlen(labels);
  /* the sum and the count take the labels without the trailing comma */
  put(s, "%s_sum%s%.*s%s %.9f\n", metric, n ? "{" : "", n ? (int)n - 1 : 0,
      labels, n ? "}" : "", 1e-9 * (double)atomic_load(ns_sum));
  put(s, "%s_count%s%.*s%s %lu\n", metric, n ? "{" : "", n ? (int)n - 1 : 0,
      labels, n ? "}" : "", cum);
}

/* The jobs: by status and pending from the store (when it told), the
 * chunks this replica computed, the store's latency. */
static void jobs(sbuf *s, srv_metrics *m) {
  pthread_mutex_lock(&m->jobs_mu);
  if (m->jobs_known) {
    static const char *const NAMES[5] = {"accepted", "running", "successful",
                                         "failed", "dismissed"};
    put(s, "# HELP stickslip_jobs Jobs in the store by status (every "
           "replica's).\n# TYPE stickslip_jobs gauge\n");
    for (int i = 0; i < 5; i++)
      put(s, "stickslip_jobs{status=\"%s\"} %ld\n", NAMES[i],
          m->jobs_by_status[i]);
    put(s,
        "# HELP stickslip_job_chunk_queue Chunks of jobs waiting to be "
        "claimed, or leased now.\n# TYPE stickslip_job_chunk_queue gauge\n"
        "stickslip_job_chunk_queue %ld\n",
        m->jobs_pending);
  }
  pthread_mutex_unlock(&m->jobs_mu);
  put(s,
      "# HELP stickslip_job_chunks_total Chunks of jobs computed and stored "
      "by this replica.\n# TYPE stickslip_job_chunks_total counter\n"
      "stickslip_job_chunks_total %lu\n",
      atomic_load(&m->job_chunks));
  put(s, "# HELP stickslip_job_items_total Items of the chunks of jobs "
         "computed and stored by this replica, by endpoint (a /batch's "
         "items, the cells of a /map or a /basins, 1 for a single answer); "
         "a /batch job's items are not in stickslip_batch_items_total.\n"
         "# TYPE stickslip_job_items_total counter\n");
  for (size_t e = 0; e < m->n; e++) {
    unsigned long k = atomic_load(&m->ep[e].job_items);
    if (k)
      put(s, "stickslip_job_items_total{endpoint=\"%s\"} %lu\n", label(m, e),
          k);
  }
  put(s, "# HELP stickslip_job_store_seconds Latency of the calls to the job "
         "store.\n# TYPE stickslip_job_store_seconds histogram\n");
  histogram(s, "stickslip_job_store_seconds", "", m->store_bucket,
            &m->store_ns_sum);
}

/* The process metrics of the Prometheus conventions, from getrusage and
 * /proc (absent where /proc is). */
static void process(sbuf *s, const srv_metrics *m) {
  struct rusage ru;
  struct rlimit rl;
  if (getrusage(RUSAGE_SELF, &ru) == 0)
    put(s,
        "# HELP process_cpu_seconds_total Total user and system CPU time "
        "spent in seconds.\n# TYPE process_cpu_seconds_total counter\n"
        "process_cpu_seconds_total %.6f\n",
        (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
            (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec);
  FILE *f = fopen("/proc/self/statm", "r");
  unsigned long pages_v, pages_r;
  if (f && fscanf(f, "%lu %lu", &pages_v, &pages_r) == 2) {
    double page = (double)sysconf(_SC_PAGESIZE);
    put(s,
        "# HELP process_virtual_memory_bytes Virtual memory size in bytes.\n"
        "# TYPE process_virtual_memory_bytes gauge\n"
        "process_virtual_memory_bytes %.0f\n"
        "# HELP process_resident_memory_bytes Resident memory size in "
        "bytes.\n# TYPE process_resident_memory_bytes gauge\n"
        "process_resident_memory_bytes %.0f\n",
        (double)pages_v * page, (double)pages_r * page);
  }
  if (f)
    fclose(f);
  DIR *dir = opendir("/proc/self/fd");
  if (dir) {
    long n = 0;
    struct dirent *de;
    while ((de = readdir(dir)))
      n += de->d_name[0] != '.';
    closedir(dir);
    put(s,
        "# HELP process_open_fds Number of open file descriptors.\n"
        "# TYPE process_open_fds gauge\nprocess_open_fds %ld\n",
        n - 1); /* the directory's own */
  }
  if (getrlimit(RLIMIT_NOFILE, &rl) == 0)
    put(s,
        "# HELP process_max_fds Maximum number of open file descriptors.\n"
        "# TYPE process_max_fds gauge\nprocess_max_fds %.0f\n",
        rl.rlim_cur == RLIM_INFINITY ? -1.0 : (double)rl.rlim_cur);
  put(s,
      "# HELP process_start_time_seconds Start time of the process since "
      "unix epoch in seconds.\n# TYPE process_start_time_seconds gauge\n"
      "process_start_time_seconds %.3f\n",
      m->start_time);
}

/* The requests waiting for a worker by endpoint, one series for each that
 * can wait (those that compute, and the job resources), 0 included: the
 * pool serves its clients round robin whatever they ask, and this says
 * which work a queue holds, cheap or long.  A /batch counts its body's parse
 * and then each of its runners that waits (a runner takes the batch's next
 * items, one after another). */
static void queued(sbuf *s, const srv_metrics *m) {
  put(s, "# HELP stickslip_queued_requests Requests waiting for a worker, by "
         "endpoint (a /batch: its parse, then each runner of its items).\n"
         "# TYPE stickslip_queued_requests gauge\n");
  for (size_t e = 0; e < m->n; e++)
    if (e + 1 == m->n ||
        (e + 2 < m->n && api_endpoint_at(e)->run_class != API_RUN_INLINE))
      put(s, "stickslip_queued_requests{endpoint=\"%s\"} %u\n", label(m, e),
          atomic_load(&m->ep[e].queued));
}

char *srv_metrics_render(srv_metrics *m) {
  sbuf s = {malloc(8192), 0, 8192};
  put(&s,
      "# HELP stickslip_build_info The version that runs, and its HTTP "
      "library.\n# TYPE stickslip_build_info gauge\n"
      "stickslip_build_info{%s} 1\n",
      m->build);
  put(&s, "# HELP stickslip_requests_total Requests by endpoint and status "
          "(those seen; 499: the client went away).\n"
          "# TYPE stickslip_requests_total counter\n");
  for (size_t e = 0; e < m->n; e++)
    for (int c = 0; c < N_STATUS; c++) {
      unsigned long k = atomic_load(&m->ep[e].status[c]);
      if (k)
        put(&s, "stickslip_requests_total{endpoint=\"%s\",code=\"%d\"} %lu\n",
            label(m, e), c + 100, k);
    }
  put(&s, "# HELP stickslip_batch_items_total Items of POST /batch by "
          "path and status.\n"
          "# TYPE stickslip_batch_items_total counter\n");
  for (size_t e = 0; e < m->n; e++)
    for (int c = 0; c < N_STATUS; c++) {
      unsigned long k = atomic_load(&m->ep[e].batch_status[c]);
      if (k)
        put(&s,
            "stickslip_batch_items_total{endpoint=\"%s\",code=\"%d\"} %lu\n",
            label(m, e), c + 100, k);
    }
  put(&s, "# HELP stickslip_errors_total Requests answered 4xx or 5xx.\n"
          "# TYPE stickslip_errors_total counter\n");
  for (size_t e = 0; e < m->n; e++) {
    unsigned long k = 0;
    for (int c = 300; c < N_STATUS; c++)
      k += atomic_load(&m->ep[e].status[c]);
    put(&s, "stickslip_errors_total{endpoint=\"%s\"} %lu\n", label(m, e), k);
  }
  put(&s, "# HELP stickslip_request_duration_seconds Latency from the first "
          "byte of the request to the last byte of the response.\n"
          "# TYPE stickslip_request_duration_seconds histogram\n");
  for (size_t e = 0; e < m->n; e++) {
    char labels[64];
    snprintf(labels, sizeof labels, "endpoint=\"%s\",", label(m, e));
    histogram(&s, "stickslip_request_duration_seconds", labels,
              m->ep[e].latency_bucket, &m->ep[e].latency_ns_sum);
  }
  put(&s,
      "# HELP stickslip_requests_in_flight Requests being served.\n"
      "# TYPE stickslip_requests_in_flight gauge\n"
      "stickslip_requests_in_flight %ld\n",
      atomic_load(&m->in_flight));
  put(&s,
      "# HELP stickslip_workers Threads of the compute pool (--workers).\n"
      "# TYPE stickslip_workers gauge\nstickslip_workers %u\n"
      "# HELP stickslip_workers_busy Threads of the compute pool running a "
      "computation or a batch's item.\n"
      "# TYPE stickslip_workers_busy gauge\nstickslip_workers_busy %u\n"
      "# HELP stickslip_queued Computations and batch items waiting for a "
      "worker.\n"
      "# TYPE stickslip_queued gauge\nstickslip_queued %u\n"
      "# HELP stickslip_queued_clients Clients with work waiting or "
      "running.\n"
      "# TYPE stickslip_queued_clients gauge\nstickslip_queued_clients %u\n",
      atomic_load(&m->workers), atomic_load(&m->busy), atomic_load(&m->waiting),
      atomic_load(&m->clients));
  queued(&s, m);
  put(&s,
      "# HELP stickslip_rejected_busy_total Requests answered 503 "
      "because their client's queue was full.\n"
      "# TYPE stickslip_rejected_busy_total counter\n"
      "stickslip_rejected_busy_total %lu\n"
      "# HELP stickslip_cancelled_total Computations dropped or stopped "
      "because their client went away.\n"
      "# TYPE stickslip_cancelled_total counter\n"
      "stickslip_cancelled_total %lu\n"
      "# HELP stickslip_slow_closed_total Connections closed because they "
      "did not deliver a request within --request-timeout.\n"
      "# TYPE stickslip_slow_closed_total counter\n"
      "stickslip_slow_closed_total %lu\n",
      atomic_load(&m->rejected_busy), atomic_load(&m->cancelled),
      atomic_load(&m->slow));
  put(&s,
      "# HELP stickslip_memory_held_bytes Bytes held by request bodies and "
      "answers in flight, counted against --memory-budget.\n"
      "# TYPE stickslip_memory_held_bytes gauge\n"
      "stickslip_memory_held_bytes %ld\n"
      "# HELP stickslip_memory_held_peak_bytes The highest value of "
      "stickslip_memory_held_bytes since the start.\n"
      "# TYPE stickslip_memory_held_peak_bytes gauge\n"
      "stickslip_memory_held_peak_bytes %ld\n"
      "# HELP stickslip_rejected_memory_total Requests "
      "answered 503 because the memory budget was spent.\n"
      "# TYPE stickslip_rejected_memory_total counter\n"
      "stickslip_rejected_memory_total %lu\n",
      atomic_load(&m->held), atomic_load(&m->held_peak),
      atomic_load(&m->rejected_memory));
  jobs(&s, m);
  process(&s, m);
  return s.p;
}
