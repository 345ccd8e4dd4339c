/*
 * pool.c: the compute pool.  A fixed set of worker threads serves the
 * queues of the clients round robin: the client served last goes to the
 * back, so a client with many requests waiting cannot starve one with a
 * single request.  Each client may have at most client_workers jobs running
 * (so that, with client_workers < workers, another client always finds a
 * free worker however long the first one's jobs are) and client_queue jobs
 * waiting; a job over that is refused at once, never kept waiting for a
 * slot.  A job that computes on threads of its own (a /map, a /basins)
 * borrows a worker for each thread beyond its own, of those free now, and
 * holds them until it ends: they count against its client's cap, and the
 * pool's threads wait while they are out, so that no client, and not the
 * pool, ever computes on more threads than --client-workers and --workers
 * allow.  A job whose client has gone away is dropped if it waits, and told
 * to stop (its cancel flag, which the core polls) if it runs.
 */
#define _POSIX_C_SOURCE 200809L
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "server.h"

typedef struct client {
  struct client *prev, *next; /* clients with jobs, in serving order */
  char key[SRV_CLIENT_KEY];
  srv_job *head, *tail; /* waiting */
  unsigned waiting, running;
} client;

struct srv_pool {
  pthread_mutex_t mu;
  pthread_cond_t work; /* a job may have become runnable */
  pthread_cond_t idle; /* a job finished */
  client *first, *last;
  srv_job *all; /* every job waiting or running (for srv_pool_watch) */
  unsigned running, waiting;
  unsigned *waiting_kind; /* waiting, by srv_job.kind (cfg.kinds of them) */
  srv_pool_cfg cfg;
  int stop;
  pthread_t *threads;
  unsigned n_threads;
};

static void client_unlink(srv_pool *p, client *c) {
  if (c->prev)
    c->prev->next = c->next;
  else
    p->first = c->next;
  if (c->next)
    c->next->prev = c->prev;
  else
    p->last = c->prev;
  c->prev = c->next = NULL;
}

static void client_append(srv_pool *p, client *c) {
  c->prev = p->last;
  c->next = NULL;
  if (p->last)
    p->last->next = c;
  else
    p->first = c;
  p->last = c;
}

static client *client_find(srv_pool *p, const char *key) {
  for (client *c = p->first; c; c = c->next)
    if (strcmp(c->key, key) == 0)
      return c;
  return NULL;
}

/* A client with nothing waiting or running is forgotten. */
static void client_release(srv_pool *p, client *c) {
  if (c->waiting == 0 && c->running == 0) {
    client_unlink(p, c);
    free(c);
  }
}

static void all_unlink(srv_pool *p, srv_job *j) {
  if (j->all_prev)
    j->all_prev->all_next = j->all_next;
  else
    p->all = j->all_next;
  if (j->all_next)
    j->all_next->all_prev = j->all_prev;
  j->all_prev = j->all_next = NULL;
}

/* Remove job @a j from its client's queue (it is there). */
static void dequeue(srv_pool *p, srv_job *j) {
  client *c = j->owner;
  srv_job **at = &c->head, *prev = NULL;
  while (*at != j) {
    prev = *at;
    at = &(*at)->next;
  }
  *at = j->next;
  if (c->tail == j)
    c->tail = prev;
  j->next = NULL;
  c->waiting--;
  p->waiting--;
  p->waiting_kind[j->kind]--;
}

/* The next job to run: the first client, in serving order, with a job
 * waiting and a running slot free; that client then goes to the back.
 * None while borrowed workers leave no slot free. */
static srv_job *take(srv_pool *p) {
  if (p->running >= p->n_threads)
    return NULL;
  for (client *c = p->first; c; c = c->next) {
    if (!c->head || c->running >= p->cfg.client_workers)
      continue;
    srv_job *j = c->head;
    dequeue(p, j);
    c->running++;
    p->running++;
    client_unlink(p, c);
    client_append(p, c);
    return j;
  }
  return NULL;
}

static void *worker(void *arg) {
  srv_pool *p = arg;
  pthread_mutex_lock(&p->mu);
  for (;;) {
    srv_job *j = NULL;
    while (!p->stop && !(j = take(p)))
      pthread_cond_wait(&p->work, &p->mu);
    if (!j)
      break;
    j->state = SRV_JOB_RUNNING;
    pthread_mutex_unlock(&p->mu);
    if (!atomic_load(&j->cancel))
      j->ops->run(j);
    pthread_mutex_lock(&p->mu);
    client *c = j->owner;
    c->running -= 1 + j->extra;
    p->running -= 1 + j->extra;
    /* The slot this job held is this thread's again: it takes the next job
     * itself, so no other thread need wake, unless the job had borrowed
     * threads, whose slots are free now too. */
    if (j->extra)
      pthread_cond_broadcast(&p->work);
    j->extra = 0;
    client_release(p, c);
    all_unlink(p, j);
    j->state = atomic_load(&j->cancel) ? SRV_JOB_CANCELLED : SRV_JOB_DONE;
    if (!p->all)
      pthread_cond_broadcast(&p->idle); /* srv_pool_wait_idle */
    pthread_mutex_unlock(&p->mu);
    j->ops->done(j); /* the job's owner may free it from here on */
    pthread_mutex_lock(&p->mu);
  }
  pthread_mutex_unlock(&p->mu);
  return NULL;
}

srv_pool *srv_pool_new(const srv_pool_cfg *cfg) {
  srv_pool *p = calloc(1, sizeof *p);
  if (!p)
    return NULL;
  p->cfg = *cfg;
  if (p->cfg.client_workers == 0)
    p->cfg.client_workers = 1;
  if (p->cfg.kinds == 0)
    p->cfg.kinds = 1;
  pthread_mutex_init(&p->mu, NULL);
  pthread_cond_init(&p->work, NULL);
  pthread_cond_init(&p->idle, NULL);
  p->threads = calloc(cfg->workers, sizeof *p->threads);
  p->waiting_kind = calloc(p->cfg.kinds, sizeof *p->waiting_kind);
  if (!p->threads || !p->waiting_kind) {
    srv_pool_free(p);
    return NULL;
  }
  for (unsigned i = 0; i < cfg->workers; i++) {
    if (pthread_create(&p->threads[i], NULL, worker, p) != 0)
      break;
    p->n_threads++;
  }
  if (p->n_threads == 0) {
    srv_pool_free(p);
    return NULL;
  }
  return p;
}

int srv_pool_submit(srv_pool *p, srv_job *j, const char *key) {
  int rc = 0;
  pthread_mutex_lock(&p->mu);
  client *c = client_find(p, key);
  if (p->stop) {
    rc = SRV_POOL_CLOSED;
  } else if (c && c->waiting >= p->cfg.client_queue) {
    rc = SRV_POOL_FULL;
  } else if (!c && !(c = calloc(1, sizeof *c))) {
    rc = SRV_POOL_NOMEM;
  } else {
    if (!c->key[0]) {
      snprintf(c->key, sizeof c->key, "%s", key);
      client_append(p, c);
    }
    j->owner = c;
    j->pool = p;
    j->extra = 0;
    j->next = NULL;
    j->state = SRV_JOB_WAITING;
    atomic_store(&j->cancel, 0);
    if (c->tail)
      c->tail->next = j;
    else
      c->head = j;
    c->tail = j;
    c->waiting++;
    p->waiting++;
    if (j->kind >= p->cfg.kinds)
      j->kind = p->cfg.kinds - 1;
    p->waiting_kind[j->kind]++;
    j->all_prev = NULL;
    j->all_next = p->all;
    if (p->all)
      p->all->all_prev = j;
    p->all = j;
    if (j->ops->queued)
      j->ops->queued(j); /* still under the lock: before any worker */
    pthread_cond_signal(&p->work);
  }
  pthread_mutex_unlock(&p->mu);
  return rc;
}

unsigned srv_pool_borrow(srv_job *j, unsigned want) {
  srv_pool *p = j->pool;
  pthread_mutex_lock(&p->mu);
  client *c = j->owner;
  unsigned n = want > j->extra ? want - j->extra : 0;
  if (c->running + n > p->cfg.client_workers)
    n = c->running < p->cfg.client_workers ? p->cfg.client_workers - c->running
                                           : 0;
  if (p->running + n > p->n_threads)
    n = p->running < p->n_threads ? p->n_threads - p->running : 0;
  c->running += n;
  p->running += n;
  j->extra += n;
  n = j->extra < want ? j->extra : want;
  pthread_mutex_unlock(&p->mu);
  return n;
}

/* Take every waiting job for which @a gone says so (all when @a all) out
 * of the pool; they are handed to done() after the lock is released. */
static void drop_waiting(srv_pool *p, int all, int state) {
  srv_job *out = NULL;
  pthread_mutex_lock(&p->mu);
  for (srv_job *j = p->all, *nx; j; j = nx) {
    nx = j->all_next;
    if (j->state != SRV_JOB_WAITING || (!all && !j->ops->gone(j)))
      continue;
    client *c = j->owner;
    dequeue(p, j);
    client_release(p, c);
    all_unlink(p, j);
    j->state = state;
    j->next = out;
    out = j;
  }
  pthread_mutex_unlock(&p->mu);
  for (srv_job *j = out, *nx; j; j = nx) {
    nx = j->next;
    j->ops->done(j);
  }
}

void srv_pool_watch(srv_pool *p) {
  /* running jobs: the flag is enough, the core polls it */
  pthread_mutex_lock(&p->mu);
  for (srv_job *j = p->all; j; j = j->all_next)
    if (j->state == SRV_JOB_RUNNING && !atomic_load(&j->cancel) &&
        j->ops->gone(j))
      atomic_store(&j->cancel, 1);
  pthread_mutex_unlock(&p->mu);
  /* waiting jobs: dropped at once */
  drop_waiting(p, 0, SRV_JOB_CANCELLED);
}

void srv_pool_load(srv_pool *p, srv_pool_load_t *out, unsigned *waiting_by,
                   size_t n) {
  unsigned clients = 0;
  pthread_mutex_lock(&p->mu);
  for (client *c = p->first; c; c = c->next)
    clients++;
  for (size_t k = 0; waiting_by && k < n; k++)
    waiting_by[k] = k < p->cfg.kinds ? p->waiting_kind[k] : 0;
  out->workers = p->n_threads;
  out->running = p->running;
  out->waiting = p->waiting;
  out->clients = clients;
  pthread_mutex_unlock(&p->mu);
}

int srv_pool_idle(srv_pool *p) {
  pthread_mutex_lock(&p->mu);
  int idle = p->waiting == 0 && p->running < p->n_threads;
  pthread_mutex_unlock(&p->mu);
  return idle;
}

void srv_pool_drain(srv_pool *p) { drop_waiting(p, 1, SRV_JOB_REFUSED); }

void srv_pool_cancel_all(srv_pool *p) {
  pthread_mutex_lock(&p->mu);
  for (srv_job *j = p->all; j; j = j->all_next)
    atomic_store(&j->cancel, 1);
  pthread_mutex_unlock(&p->mu);
}

int srv_pool_wait_idle(srv_pool *p, double seconds) {
  struct timespec dl;
  clock_gettime(CLOCK_REALTIME, &dl);
  dl.tv_sec += (time_t)seconds;
  dl.tv_nsec += (long)((seconds - (double)(time_t)seconds) * 1e9);
  if (dl.tv_nsec >= 1000000000L) {
    dl.tv_sec++;
    dl.tv_nsec -= 1000000000L;
  }
  pthread_mutex_lock(&p->mu);
  int rc = 0;
  while (p->all && rc == 0)
    rc = pthread_cond_timedwait(&p->idle, &p->mu, &dl);
  int idle = p->all == NULL;
  pthread_mutex_unlock(&p->mu);
  return idle;
}

void srv_pool_free(srv_pool *p) {
  if (!p)
    return;
  pthread_mutex_lock(&p->mu);
  p->stop = 1;
  pthread_cond_broadcast(&p->work);
  pthread_mutex_unlock(&p->mu);
  for (unsigned i = 0; i < p->n_threads; i++)
    pthread_join(p->threads[i], NULL);
  free(p->threads);
  free(p->waiting_kind);
  pthread_cond_destroy(&p->work);
  pthread_cond_destroy(&p->idle);
  pthread_mutex_destroy(&p->mu);
  free(p);
}
