/*
 * metrics.c: counters and latency histograms in the Prometheus text format.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "server.h"

const char *const srv_ep_names[SRV_EP_COUNT] = {
    "orbit",   "simulate", "stability", "health",
    "version", "openapi",  "metrics",   "other"};

const double srv_bucket_bounds[SRV_BUCKETS] = {0.0001, 0.00025, 0.0005, 0.001,
                                               0.0025, 0.005,   0.01,   0.025,
                                               0.05,   0.1,     1.0,    10.0};

void srv_metrics_observe(srv_metrics *m, int ep, int status, double seconds) {
  int cls = status / 100;
  if (ep < 0 || ep >= SRV_EP_COUNT)
    ep = SRV_EP_OTHER;
  if (cls < 1 || cls > 5)
    cls = 5;
  atomic_fetch_add(&m->requests[ep], 1);
  atomic_fetch_add(&m->status_class[ep][cls], 1);
  atomic_fetch_add(&m->latency_us_sum[ep], (unsigned long)(seconds * 1e6));
  int b = 0;
  while (b < SRV_BUCKETS && seconds > srv_bucket_bounds[b])
    b++;
  atomic_fetch_add(&m->latency_bucket[ep][b], 1);
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

#include <stdarg.h>
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

char *srv_metrics_render(const srv_metrics *m) {
  sbuf s = {malloc(8192), 0, 8192};
  put(&s, "# HELP stickslip_requests_total Requests by endpoint and status "
          "class.\n# TYPE stickslip_requests_total counter\n");
  for (int e = 0; e < SRV_EP_COUNT; e++)
    for (int c = 1; c <= 5; c++)
      put(&s, "stickslip_requests_total{endpoint=\"%s\",code=\"%dxx\"} %lu\n",
          srv_ep_names[e], c, atomic_load(&m->status_class[e][c]));
  put(&s, "# HELP stickslip_errors_total Requests answered 4xx or 5xx.\n"
          "# TYPE stickslip_errors_total counter\n");
  for (int e = 0; e < SRV_EP_COUNT; e++)
    put(&s, "stickslip_errors_total{endpoint=\"%s\"} %lu\n", srv_ep_names[e],
        atomic_load(&m->status_class[e][4]) +
            atomic_load(&m->status_class[e][5]));
  put(&s, "# HELP stickslip_request_duration_seconds Latency from the first "
          "byte of the request to the last byte of the response.\n"
          "# TYPE stickslip_request_duration_seconds histogram\n");
  for (int e = 0; e < SRV_EP_COUNT; e++) {
    unsigned long cum = 0;
    for (int b = 0; b < SRV_BUCKETS; b++) {
      cum += atomic_load(&m->latency_bucket[e][b]);
      put(&s,
          "stickslip_request_duration_seconds_bucket{endpoint=\"%s\",le=\"%g\"}"
          " %lu\n",
          srv_ep_names[e], srv_bucket_bounds[b], cum);
    }
    cum += atomic_load(&m->latency_bucket[e][SRV_BUCKETS]);
    put(&s,
        "stickslip_request_duration_seconds_bucket{endpoint=\"%s\",le=\"+Inf\"}"
        " %lu\n",
        srv_ep_names[e], cum);
    put(&s, "stickslip_request_duration_seconds_sum{endpoint=\"%s\"} %.6f\n",
        srv_ep_names[e], 1e-6 * (double)atomic_load(&m->latency_us_sum[e]));
    put(&s, "stickslip_request_duration_seconds_count{endpoint=\"%s\"} %lu\n",
        srv_ep_names[e], cum);
  }
  put(&s,
      "# HELP stickslip_requests_in_flight Requests being served.\n"
      "# TYPE stickslip_requests_in_flight gauge\n"
      "stickslip_requests_in_flight %ld\n",
      atomic_load(&m->in_flight));
  put(&s,
      "# HELP stickslip_rejected_busy_total Requests answered 503 "
      "because every compute slot stayed busy.\n"
      "# TYPE stickslip_rejected_busy_total counter\n"
      "stickslip_rejected_busy_total %lu\n",
      atomic_load(&m->rejected_busy));
  return s.p;
}
