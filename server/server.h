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

#define SRV_BUCKETS 12

/*
 * Counters and latency histograms by endpoint: one row per row of the api's
 * endpoint table (api_endpoint_at), and a last row for requests that matched
 * none (404, 405).
 */
typedef struct srv_metrics srv_metrics;

srv_metrics *srv_metrics_new(void); /* NULL when out of memory */
void srv_metrics_free(srv_metrics *m);
/* @a ep: an endpoint index, or anything out of range for "other". */
void srv_metrics_observe(srv_metrics *m, size_t ep, int status, double seconds);
void srv_metrics_busy(srv_metrics *m); /* a 503 for a busy slot */
long srv_metrics_in_flight(srv_metrics *m, int delta);
char *srv_metrics_render(srv_metrics *m); /* malloc'd */

/** Start the daemon; prints the URL to stderr when ready.  NULL on error. */
struct srv_daemon;
struct srv_daemon *srv_start(const srv_config *cfg);
/** Stop accepting, let requests in flight finish (up to cfg->drain s), stop. */
void srv_stop(struct srv_daemon *d);

#endif
