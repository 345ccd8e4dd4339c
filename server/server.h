/*
 * server.h: stickslipd, the HTTP daemon (libmicrohttpd).
 */
#ifndef SS_SERVER_H
#define SS_SERVER_H

#include <stdatomic.h>
#include <stddef.h>

#include "stickslip_api.h"

#define SRV_MAX_PROXIES 16
#define SRV_MAX_ORIGINS 16

/** Everything a flag or an environment variable can set. */
typedef struct srv_config {
  char bind[64];           /**< --bind, STICKSLIP_BIND (127.0.0.1) */
  int port;                /**< --port, STICKSLIP_PORT (8080; 0: any free) */
  api_limits lim;          /**< per-request limits */
  unsigned max_conn;       /**< --max-connections (2048) */
  unsigned per_ip;         /**< --per-ip-connections (256) */
  unsigned reserved;       /**< --reserved-connections (256): the last
                                slots, for addresses holding few */
  unsigned timeout;        /**< --connection-timeout seconds (10) */
  unsigned workers;        /**< --workers: computations at once (cores) */
  unsigned client_workers; /**< --client-workers: of one client (workers-1) */
  unsigned client_queue;   /**< --client-queue: waiting, per client (64) */
  double request_timeout;  /**< --request-timeout: headers and body (10) */
  double drain;            /**< --drain seconds at shutdown (15) */
  size_t memory_mb;        /**< --memory-budget, MiB (256) */
  size_t stream_above;     /**< answers larger than this are streamed */
  unsigned batch_parallel; /**< --batch-parallel: items of a batch in
                                flight at once (workers) */
  int quiet;               /**< --quiet: no access log */
  int log_plain;           /**< --log-format plain (default json) */
  /** --trusted-proxy (repeatable): peers whose X-Forwarded-For names the
   *  client, for the per-client queues */
  char trusted[SRV_MAX_PROXIES][48];
  int n_trusted;
  /** --cors-origin (repeatable): origins whose pages may call the daemon
   *  (scheme://host[:port], or * for any); none by default */
  char origins[SRV_MAX_ORIGINS][128];
  int n_origins;
  /* jobs (POST with Prefer: respond-async; server/jobs.c) */
  int no_jobs;            /**< --no-jobs: Prefer: respond-async is ignored */
  char job_store[512];    /**< --job-store URI ("": no store; stickslipd
                               defaults to sqlite:<state-dir>/jobs.sqlite) */
  char state_dir[256];    /**< --state-dir (./stickslip-state, or
                               $STATE_DIRECTORY) */
  unsigned job_workers;   /**< --job-workers: runner threads (1) */
  double job_max_seconds; /**< --job-max-seconds: compute time of a job */
  double job_ttl;         /**< --job-ttl: seconds a finished job is kept */
  double job_lease;       /**< --job-lease: seconds a claim of a chunk
                               holds unless renewed (30) */
  size_t max_job_body;    /**< --max-job-body: a job's request body */
  size_t max_job_items;   /**< --max-job-items: items of a /batch job */
} srv_config;

/* ---- the compute pool (pool.c) ----------------------------------------- */

#define SRV_CLIENT_KEY 64 /* a client's key: its address as text */
#define SRV_REQUEST_ID 64 /* the longest X-Request-Id taken from a client */

enum {
  SRV_JOB_WAITING = 1,
  SRV_JOB_RUNNING,
  SRV_JOB_DONE,      /* ran to its end */
  SRV_JOB_CANCELLED, /* its client went away: dropped, or stopped */
  SRV_JOB_REFUSED    /* still waiting when the daemon shut down */
};

typedef struct srv_job srv_job;

/* What the pool does with a kind of job (a request, an item of a batch). */
typedef struct srv_job_ops {
  void (*queued)(srv_job *); /* under the lock, before any worker sees it;
                                NULL: nothing */
  void (*run)(srv_job *);    /* on a worker */
  void (*done)(srv_job *);   /* after it ran, or was dropped; no lock held */
  int (*gone)(srv_job *);    /* whether its client has gone away (polled by
                                srv_pool_watch under the pool's lock) */
} srv_job_ops;

/* A unit of work, embedded in what it computes. */
struct srv_job {
  const srv_job_ops *ops;
  atomic_int cancel;    /* set when the client is gone; the core polls it */
  int state;            /* SRV_JOB_*, under the pool's lock */
  struct srv_job *next; /* in its client's queue */
  struct srv_job *all_prev, *all_next; /* waiting or running */
  void *owner;                         /* its client */
  struct srv_pool *pool;               /* the pool it was submitted to */
  unsigned extra; /* workers borrowed for its own threads (srv_pool_borrow) */
  unsigned kind;  /* what it is counted as while it waits (srv_pool_cfg.kinds):
                     set by the caller before srv_pool_submit */
};

typedef struct srv_pool_cfg {
  unsigned workers;        /* threads */
  unsigned client_workers; /* jobs of one client running at once */
  unsigned client_queue;   /* jobs of one client waiting */
  unsigned kinds; /* the kinds of job counted apart while they wait (the
                     last counts every job of a kind beyond); 0: 1 */
} srv_pool_cfg;

typedef struct srv_pool srv_pool;

enum { SRV_POOL_FULL = 1, SRV_POOL_CLOSED = 2, SRV_POOL_NOMEM = 3 };

srv_pool *srv_pool_new(const srv_pool_cfg *cfg); /* NULL on failure */
/* Queue @a j for the client @a key: 0, or SRV_POOL_FULL (that client's
 * queue is full), SRV_POOL_CLOSED, SRV_POOL_NOMEM. */
int srv_pool_submit(srv_pool *p, srv_job *j, const char *key);
/* For running job @a j, which computes on threads of its own (a /map, a
 * /basins), up to @a want workers beyond its own, borrowed as its client's
 * cap and the pool have them free now: the number it holds (perhaps 0).
 * They count as its client's running jobs and keep as many of the pool's
 * threads idle until @a j ends. */
unsigned srv_pool_borrow(srv_job *j, unsigned want);
/* Flag the running jobs whose client is gone (ops->gone), and drop the
 * waiting ones (done() with SRV_JOB_CANCELLED). */
void srv_pool_watch(srv_pool *p);
/* What the pool holds now. */
typedef struct srv_pool_load_t {
  unsigned workers; /* threads */
  unsigned running; /* jobs running: busy workers */
  unsigned waiting; /* jobs queued (requests and batch items) */
  unsigned clients; /* clients with a job waiting or running */
} srv_pool_load_t;
/* @a waiting_by: NULL, or room for @a n counts, filled with the jobs waiting
 * of each kind (0 beyond the pool's kinds). */
void srv_pool_load(srv_pool *p, srv_pool_load_t *out, unsigned *waiting_by,
                   size_t n);
/* Whether a worker is free and no job waits: work done elsewhere now (on
 * the I/O thread) then takes no turn from a job queued. */
int srv_pool_idle(srv_pool *p);
/* Drop every waiting job (done() with SRV_JOB_REFUSED). */
void srv_pool_drain(srv_pool *p);
/* Flag every job to stop. */
void srv_pool_cancel_all(srv_pool *p);
/* Wait until no job waits or runs, at most @a seconds: 1 if idle. */
int srv_pool_wait_idle(srv_pool *p, double seconds);
/* Stop the workers (after the jobs they run) and free the pool. */
void srv_pool_free(srv_pool *p);

/* ---- metrics (metrics.c) ------------------------------------------------ */

#define SRV_BUCKETS 18

/*
 * Counters and latency histograms by endpoint: one row per row of the api's
 * endpoint table (api_endpoint_at), and a last row for requests that matched
 * none (404, 405).
 */
typedef struct srv_metrics srv_metrics;

srv_metrics *srv_metrics_new(void); /* NULL when out of memory */
void srv_metrics_free(srv_metrics *m);
/* The labels of stickslip_build_info. */
void srv_metrics_build(srv_metrics *m, const char *version,
                       const char *transport);
/* The row of the job resources (/jobs...) in srv_metrics_observe. */
size_t srv_metrics_jobs_row(void);
/* @a ep: an endpoint index, srv_metrics_jobs_row(), or anything else for
 * "other". */
void srv_metrics_observe(srv_metrics *m, size_t ep, int status, double seconds);
void srv_metrics_busy(srv_metrics *m);      /* a 503 for a full queue */
void srv_metrics_cancelled(srv_metrics *m); /* work of a client gone away */
void srv_metrics_slow(srv_metrics *m);      /* a connection past its deadline */
void srv_metrics_over_budget(srv_metrics *m); /* a 503 for the memory budget */
/* Bytes held by bodies and answers: add @a delta, return the new total. */
long srv_metrics_held(srv_metrics *m, long delta);
long srv_metrics_in_flight(srv_metrics *m, int delta);
/* An item of a batch answered @a status; @a ep as for srv_metrics_observe. */
void srv_metrics_batch_item(srv_metrics *m, size_t ep, int status);
/* The pool's load, for the next srv_metrics_render. */
void srv_metrics_pool(srv_metrics *m, srv_pool *p);
/* A chunk of a job of endpoint @a ep (as for srv_metrics_observe), of
 * @a items items, computed and stored by this replica. */
void srv_metrics_job_chunk(srv_metrics *m, size_t ep, long items);
/* A call to the job store took @a seconds. */
void srv_metrics_store(srv_metrics *m, double seconds);
/* The jobs by status (indexed by store_status) and the chunks pending, for
 * the next srv_metrics_render; @a known 0 when the store could not tell
 * (no job metrics are rendered then). */
void srv_metrics_jobs(srv_metrics *m, int known, const long by_status[5],
                      long pending);
char *srv_metrics_render(srv_metrics *m); /* malloc'd */

/** Start the daemon; prints the URL to stderr when ready.  NULL on error,
 *  said on stderr; errno EADDRINUSE when its port is taken. */
struct srv_daemon;
struct srv_daemon *srv_start(const srv_config *cfg);
/** Hand the daemon a connected socket @a fd, as if it had accepted it from
 *  @a addr (the HTTP fuzz target feeds it one end of a socketpair).  The
 *  daemon owns @a fd from then on, also on failure.  0, or -1. */
struct sockaddr;
int srv_add_connection(struct srv_daemon *d, int fd,
                       const struct sockaddr *addr, unsigned addrlen);

/* Connections libmicrohttpd has started serving (NOTIFY_CONNECTION), since
 * the daemon started: a connection handed over by srv_add_connection
 * counts once the daemon's thread has taken it up. */
unsigned long srv_connections_started(struct srv_daemon *d);

/* The port the daemon listens on (the one the system chose for port 0). */
int srv_port(struct srv_daemon *d);
/* The URL it listens on, http://ADDR:PORT ([ADDR] for IPv6), as it
 * prints it when it is ready. */
const char *srv_url(struct srv_daemon *d);

/* What the monitor knows of one connection, for diagnosing a stall. */
typedef struct srv_conn_state {
  int receiving; /* its current request is still being received */
  int shut;      /* the monitor has shut it down */
  double age;    /* seconds since its current request started */
  int requests;  /* requests the handler has seen on it */
  int suspended; /* a computation holds it suspended */
  int resumed;   /* ... and the pool has resumed it with an answer */
} srv_conn_state;

/* The connection on the daemon's socket @a fd, or (fd < 0) the one whose
 * peer is at local TCP port @a peer_port: 0 with its state, or -1 when
 * the monitor does not watch such a connection. */
int srv_connection_watched(struct srv_daemon *d, int fd, int peer_port,
                           srv_conn_state *st);
/** The text of the IPv4 or IPv6 address @a s as the daemon writes a
 *  client's address (inet_ntop), into @a out; 0, or -1 when @a s is not
 *  an address. */
int srv_address_text(const char *s, char *out, size_t n);
/** Stop accepting, let requests in flight finish (up to cfg->drain s), stop. */
void srv_stop(struct srv_daemon *d);

#endif
