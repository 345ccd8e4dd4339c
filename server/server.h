/*
 * server.h: stickslipd, the HTTP daemon (libmicrohttpd).
 */
#ifndef SS_SERVER_H
#define SS_SERVER_H

#include <stdatomic.h>
#include <stddef.h>

#include "stickslip_api.h"

/** Everything a flag or an environment variable can set. */
typedef struct srv_config {
  char bind[64];        /**< --bind, STICKSLIP_BIND (127.0.0.1) */
  int port;             /**< --port, STICKSLIP_PORT (8080; 0: any free) */
  api_limits lim;       /**< per-request limits */
  unsigned max_conn;    /**< --max-connections (256) */
  unsigned per_ip;      /**< --per-ip-connections (64) */
  unsigned timeout;     /**< --connection-timeout seconds (10) */
  unsigned workers;     /**< --workers: computations at once (cores) */
  double queue_timeout; /**< --queue-timeout seconds (2) */
  double drain;         /**< --drain seconds at shutdown (8) */
  int quiet;            /**< --quiet: no access log */
} srv_config;

/* Endpoints, for metrics. */
enum {
  SRV_EP_ORBIT,
  SRV_EP_SIMULATE,
  SRV_EP_STABILITY,
  SRV_EP_HEALTH,
  SRV_EP_VERSION,
  SRV_EP_OPENAPI,
  SRV_EP_METRICS,
  SRV_EP_OTHER,
  SRV_EP_COUNT
};

#define SRV_BUCKETS 12

typedef struct srv_metrics {
  atomic_ulong requests[SRV_EP_COUNT];
  atomic_ulong status_class[SRV_EP_COUNT][6]; /* 1xx..5xx by index 1..5 */
  atomic_ulong latency_us_sum[SRV_EP_COUNT];
  atomic_ulong latency_bucket[SRV_EP_COUNT][SRV_BUCKETS + 1];
  atomic_long in_flight;
  atomic_ulong rejected_busy;
} srv_metrics;

extern const char *const srv_ep_names[SRV_EP_COUNT];
extern const double srv_bucket_bounds[SRV_BUCKETS];

void srv_metrics_observe(srv_metrics *m, int ep, int status, double seconds);
char *srv_metrics_render(const srv_metrics *m); /* malloc'd */

/** Start the daemon; prints the URL to stderr when ready.  NULL on error. */
struct srv_daemon;
struct srv_daemon *srv_start(const srv_config *cfg);
/** Stop accepting, let requests in flight finish (up to cfg->drain s), stop. */
void srv_stop(struct srv_daemon *d);

#endif
