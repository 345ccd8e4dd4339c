/*
 * monitor.c: the connections, and the watch over them.
 *
 * A new connection is taken or refused by its address's count of
 * connections (srv__accept): a per-address limit, and a reserve of the
 * last slots for addresses that hold few.
 *
 * Each TCP connection is on a list from its start to its close, with the
 * time its current request started.  While a connection is suspended
 * libmicrohttpd does not look at its socket, so a monitor thread does,
 * every MONITOR_MS: a peer that has closed its end has its waiting work
 * dropped and its running work flagged (the core polls the flag).  The
 * monitor also closes connections that do not deliver a whole request
 * (headers and body) within request_timeout of their start or of the end
 * of their previous request: libmicrohttpd's own timeout counts idle time
 * only, which a byte every few seconds resets.
 *
 * And it gives the heap back.  Answers held for clients that read slowly
 * are freed in any order, and glibc's malloc keeps freed memory for reuse
 * (in every arena a thread has used): after 256 clients left their /batch
 * answers unread the daemon stayed at 74-113 MB of RSS against 9 MB idle.
 * So once the bytes held against the memory budget have fallen TRIM_STEP
 * below their high mark since the last trim, and when they are back to 0
 * from a mark of TRIM_IDLE or more (not after every small answer),
 * malloc_trim returns the free pages of every arena to the
 * system (a few milliseconds at a few hundred megabytes, here on the
 * monitor's thread).
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <malloc.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <time.h>

#include "internal.h"

#define MONITOR_MS 20
#define TRIM_STEP (32L << 20)
#define TRIM_IDLE (1L << 20)

/* ---- the connections ----------------------------------------------------- */

/* The key of the address @a sa: its text, or "?". */
static void address_key(const struct sockaddr *sa, char *key, size_t n) {
  snprintf(key, n, "?");
  if (sa && sa->sa_family == AF_INET)
    inet_ntop(AF_INET, &((const struct sockaddr_in *)sa)->sin_addr, key,
              (socklen_t)n);
  else if (sa && sa->sa_family == AF_INET6)
    inet_ntop(AF_INET6, &((const struct sockaddr_in6 *)sa)->sin6_addr, key,
              (socklen_t)n);
}

static void client_key(struct MHD_Connection *c, char *key, size_t n) {
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
  address_key(ci ? ci->client_addr : NULL, key, n);
}

static int peer_port(struct MHD_Connection *c) {
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
  const struct sockaddr *sa = ci ? ci->client_addr : NULL;
  if (sa && sa->sa_family == AF_INET)
    return ntohs(((const struct sockaddr_in *)sa)->sin_port);
  if (sa && sa->sa_family == AF_INET6)
    return ntohs(((const struct sockaddr_in6 *)sa)->sin6_port);
  return 0;
}

/* An address may hold --per-ip-connections; once --reserved-connections
 * or fewer slots are free (of --max-connections, which
 * libmicrohttpd enforces), only one holding fewer than
 * SRV__FEW_CONNECTIONS: two or three addresses that keep every slot they
 * can get leave the reserve to the others.  A trusted proxy speaks for
 * many clients: only --max-connections bounds it. */
enum MHD_Result srv__accept(void *cls, const struct sockaddr *addr,
                            socklen_t addrlen) {
  struct srv_daemon *d = cls;
  char key[SRV_CLIENT_KEY];
  long total;
  (void)addrlen;
  address_key(addr, key, sizeof key);
  if (srv__trusted(d, key))
    return MHD_YES;
  long mine = srv__tally_get(d->conns, key, NULL, &total);
  if (mine >= (long)d->cfg.per_ip ||
      (total + (long)d->cfg.reserved >= (long)d->cfg.max_conn &&
       mine >= SRV__FEW_CONNECTIONS))
    return MHD_NO;
  return MHD_YES;
}

/* libmicrohttpd's NOTIFY_CONNECTION: a connection joins the list at its
 * start, and leaves it at its close; its address's count of connections
 * with it. */
void srv__connection(void *cls, struct MHD_Connection *c, void **socket_ctx,
                     enum MHD_ConnectionNotificationCode toe) {
  struct srv_daemon *d = cls;
  srv__conn *cn = *socket_ctx;
  if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
    atomic_fetch_add(&d->conns_started, 1);
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (!ci || !(cn = calloc(1, sizeof *cn)))
      return;
    cn->fd = ci->connect_fd;
    cn->start = srv__now();
    cn->receiving = 1;
    client_key(c, cn->key, sizeof cn->key);
    cn->peer_port = peer_port(c);
    srv__wire_open(cn);
    srv__tally_add(d->conns, cn->key, 1);
    pthread_mutex_lock(&d->mu);
    cn->next = d->conn_list;
    if (d->conn_list)
      d->conn_list->prev = cn;
    d->conn_list = cn;
    pthread_mutex_unlock(&d->mu);
    *socket_ctx = cn;
    return;
  }
  if (!cn)
    return;
  srv__wire_close(cn); /* libmicrohttpd closes the socket after */
  srv__tally_add(d->conns, cn->key, -1);
  pthread_mutex_lock(&d->mu);
  if (cn->prev)
    cn->prev->next = cn->next;
  else
    d->conn_list = cn->next;
  if (cn->next)
    cn->next->prev = cn->prev;
  pthread_mutex_unlock(&d->mu);
  free(cn);
  *socket_ctx = NULL;
}

void srv__receiving(struct srv_daemon *d, srv__conn *cn, int receiving) {
  if (!cn)
    return;
  pthread_mutex_lock(&d->mu);
  if (receiving)
    cn->start = srv__now();
  cn->receiving = receiving;
  pthread_mutex_unlock(&d->mu);
}

/* ---- the monitor --------------------------------------------------------- */

/* Whether the peer of socket @a fd has closed its end: a read that finds
 * the end of the stream (or a reset) says so; pending bytes (a pipelined
 * request) or nothing to read say it is still there. */
int srv__peer_closed(int fd) {
  char b;
  if (fd < 0 || srv__wire_pending(fd))
    return 0;
  ssize_t k = recv(fd, &b, 1, MSG_PEEK | MSG_DONTWAIT);
  return k == 0 ||
         (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
}

/* Close the connections that are past their deadline for a request. */
static void reap_slow(struct srv_daemon *d) {
  double t = srv__now();
  pthread_mutex_lock(&d->mu);
  for (srv__conn *cn = d->conn_list; cn; cn = cn->next)
    if (cn->receiving && !cn->shut && t - cn->start > d->cfg.request_timeout) {
      shutdown(cn->fd, SHUT_RDWR);
      cn->shut = 1;
      srv_metrics_slow(d->metrics);
    }
  pthread_mutex_unlock(&d->mu);
}

/* The heap given back after a burst: @a high is the most the budget held
 * since the last trim. */
static void trim(struct srv_daemon *d, long *high) {
  long now = srv_metrics_held(d->metrics, 0);
  if (now > *high)
    *high = now;
  if (*high - now >= TRIM_STEP || (now == 0 && *high >= TRIM_IDLE)) {
    malloc_trim(0);
    *high = now;
  }
}

void *srv__monitor(void *arg) {
  struct srv_daemon *d = arg;
  struct timespec ts = {0, MONITOR_MS * 1000000L};
  long high = 0;
  while (!atomic_load(&d->monitor_stop)) {
    srv_pool_watch(d->pool);
    reap_slow(d);
    trim(d, &high);
    nanosleep(&ts, NULL);
  }
  return NULL;
}

/* ---- diagnosis ----------------------------------------------------------- */

unsigned long srv_connections_started(struct srv_daemon *d) {
  return atomic_load(&d->conns_started);
}

int srv_connection_watched(struct srv_daemon *d, int fd, int peer_port,
                           srv_conn_state *st) {
  int found = -1;
  pthread_mutex_lock(&d->mu);
  for (srv__conn *cn = d->conn_list; cn && found; cn = cn->next)
    if (fd >= 0 ? cn->fd == fd : cn->peer_port == peer_port) {
      st->receiving = cn->receiving;
      st->shut = cn->shut;
      st->age = srv__now() - cn->start;
      st->requests = atomic_load(&cn->requests);
      st->suspended = atomic_load(&cn->suspended);
      st->resumed = atomic_load(&cn->resumed);
      found = 0;
    }
  pthread_mutex_unlock(&d->mu);
  return found;
}
