/*
 * batch.c: POST /batch: its body parsed and its items computed in the
 * pool, its answer streamed a line per item as each is done.
 *
 * The body is parsed on a worker (srv__batch_open, a job of the batch's
 * client), and the I/O thread starts the answer when the pool resumes the
 * request with the items (srv__batch_start).
 * A batch's answer is one chunked response whose lines are written as its
 * items are done.  Its items are jobs of the pool like any request, in the
 * queue of the batch's client; at most batch_parallel of them are in flight
 * (queued, running, or done with a line not yet wholly written), so a
 * batch holds at most that many answers, and its client's other requests
 * still get their turn.  When no line is ready the response's reader
 * suspends the connection, and the next item done resumes it.  When the
 * client goes away the items that wait are dropped and the one that runs
 * is told to stop, as for any request.
 */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include "internal.h"

typedef struct bitem {
  srv_job job; /* first: a job is its item */
  srv__batch *b;
  size_t i;
  api_response ar;
  struct bitem *next; /* in the batch's list of items done */
} bitem;

struct srv__batch {
  pthread_mutex_t mu;
  struct srv_daemon *d;
  struct MHD_Connection *c; /* NULL once the request has completed */
  api_batch *ab;
  char key[SRV_CLIENT_KEY];
  atomic_int fd;   /* of the connection; -1 once it has completed */
  atomic_int gone; /* the client went away: no more items */
  size_t n, next;  /* items, and the next one to send to the pool */
  size_t in_flight, in_pool;
  size_t ok, failed;
  bitem *ready, *ready_tail; /* done, in the order they were done */
  api_stream *line;          /* the line being written */
  long line_held;
  char *last; /* the last line, once every item's line is written */
  size_t last_len, last_off;
  int waiting; /* the connection is suspended until a line is ready */
  int refs;    /* the response, and each item in the pool */
  long held;   /* bytes counted against the memory budget */
  double t0;
  size_t sent; /* bytes of the answer written */
  /* gzip: each piece of lines deflated with a sync flush, so that the
   * client can read each line as soon as it is written */
  int gz, gz_finishing, gz_end;
  z_stream zs;
  char *gz_in;
};

static void batch_hold(srv__batch *b, long bytes) {
  b->held += bytes;
  srv__held(b->d, b->key, bytes);
}

static void batch_free(srv__batch *b) {
  if (b->gz)
    deflateEnd(&b->zs);
  free(b->gz_in);
  while (b->ready) {
    bitem *it = b->ready;
    b->ready = it->next;
    api_response_free(&it->ar);
    free(it);
  }
  api_stream_free(b->line);
  free(b->last);
  api_batch_free(b->ab);
  srv__held(b->d, b->key, -b->held);
  pthread_mutex_destroy(&b->mu);
  free(b);
}

static int batch_gone(srv__batch *b) {
  return atomic_load(&b->gone) || srv__peer_closed(atomic_load(&b->fd));
}

static int item_gone(srv_job *j) { return batch_gone(((bitem *)j)->b); }

/* An item's answer is in: to the list of lines to write (under b->mu). */
static void item_ready(srv__batch *b, bitem *it) {
  it->next = NULL;
  if (b->ready_tail)
    b->ready_tail->next = it;
  else
    b->ready = it;
  b->ready_tail = it;
}

static void item_run(srv_job *j) {
  bitem *it = (bitem *)j;
  srv__batch *b = it->b;
  struct srv_daemon *d = b->d;
  if (srv__over_budget(d, b->key)) {
    srv__budget_problem(d, b->key, &it->ar);
  } else {
    api_server_info info = srv__server_info(d, &it->job);
    api_batch_run(b->ab, it->i, &d->cfg.lim, &info, &it->ar);
  }
  pthread_mutex_lock(&b->mu);
  batch_hold(b, (long)it->ar.held);
  pthread_mutex_unlock(&b->mu);
}

static void dispatch(srv__batch *b);

static void item_done(srv_job *j) {
  bitem *it = (bitem *)j;
  srv__batch *b = it->b;
  pthread_mutex_lock(&b->mu);
  b->in_pool--;
  b->refs--;
  if (j->state == SRV_JOB_CANCELLED && batch_gone(b)) {
    atomic_store(&b->gone, 1);
    srv_metrics_cancelled(b->d->metrics);
    batch_hold(b, -(long)it->ar.held);
    api_response_free(&it->ar);
    free(it);
    b->in_flight--;
  } else {
    if (j->state == SRV_JOB_REFUSED)
      api_problem(&it->ar, API_P_SHUTTING_DOWN,
                  "the server is shutting down; retry on another replica or "
                  "later",
                  NULL, NULL, 0);
    item_ready(b, it);
    dispatch(b);
  }
  if (b->waiting && b->c) {
    b->waiting = 0;
    MHD_resume_connection(b->c);
  }
  int last = b->refs == 0;
  pthread_mutex_unlock(&b->mu);
  if (last)
    batch_free(b);
}

static const srv_job_ops ITEM_JOB = {NULL, item_run, item_done, item_gone};

/* An item answered at once, without the pool (under b->mu). */
static void item_now(srv__batch *b, bitem *it, api_problem_kind kind,
                     const char *detail) {
  api_problem(&it->ar, kind, detail, NULL, NULL, 0);
  item_ready(b, it);
}

/* Send items to the pool while fewer than batch_parallel are in flight
 * (under b->mu).  When the client's queue is full or the memory budget (or
 * the client's share of it) is spent, wait for an item in flight to finish;
 * with none in flight, the item is answered 503 as a request would be. */
static void dispatch(srv__batch *b) {
  struct srv_daemon *d = b->d;
  while (!atomic_load(&b->gone) && b->next < b->n &&
         b->in_flight < d->cfg.batch_parallel) {
    bitem *it = calloc(1, sizeof *it);
    if (!it)
      return; /* a line written or an item done will try again */
    it->b = b;
    it->i = b->next;
    it->job.ops = &ITEM_JOB;
    int rc;
    if (atomic_load(&d->draining)) {
      item_now(b, it, API_P_SHUTTING_DOWN, "the server is shutting down");
    } else if (srv__over_budget(d, b->key)) {
      if (b->in_flight > 0) {
        free(it);
        return;
      }
      srv__budget_problem(d, b->key, &it->ar);
      item_ready(b, it);
    } else if ((rc = srv_pool_submit(d->pool, &it->job, b->key)) != 0) {
      if (rc == SRV_POOL_FULL && b->in_flight > 0) {
        free(it);
        return;
      }
      if (rc == SRV_POOL_FULL)
        srv_metrics_busy(d->metrics);
      item_now(b, it,
               rc == SRV_POOL_FULL    ? API_P_OVERLOADED
               : rc == SRV_POOL_NOMEM ? API_P_OUT_OF_MEMORY
                                      : API_P_SHUTTING_DOWN,
               rc == SRV_POOL_FULL ? "this client's queue is full; retry "
                                     "the item after a second"
                                   : "the item could not be queued");
    } else {
      b->in_pool++;
      b->refs++;
    }
    b->next++;
    b->in_flight++;
  }
}

/* The next line to write, into b->line or b->last (under b->mu); 0 when
 * there is none yet, -1 when out of memory. */
static int next_line(srv__batch *b) {
  if (b->ready) {
    bitem *it = b->ready;
    if (!(b->ready = it->next))
      b->ready_tail = NULL;
    if (it->ar.status == 200)
      b->ok++;
    else
      b->failed++;
    srv_metrics_batch_item(b->d->metrics, api_batch_endpoint(b->ab, it->i),
                           it->ar.status);
    size_t held;
    long answer = (long)it->ar.held;
    b->line = api_batch_line(b->ab, it->i, &it->ar, &held);
    free(it);
    batch_hold(b, (long)held - answer);
    b->line_held = (long)held;
    return b->line ? 1 : -1;
  }
  if (b->next == b->n && b->in_flight == 0 && !b->last) {
    api_response done;
    api_batch_done(b->ok, b->failed, srv__now() - b->t0, &done);
    b->last = done.body;
    b->last_len = done.len;
    return b->last ? 1 : -1;
  }
  return 0;
}

/* The reader of a batch's response, on the I/O thread. */
static ssize_t batch_read(void *cls, uint64_t pos, char *buf, size_t max) {
  srv__batch *b = cls;
  size_t got = 0;
  (void)pos;
  pthread_mutex_lock(&b->mu);
  if (atomic_load(&b->gone)) {
    pthread_mutex_unlock(&b->mu);
    return MHD_CONTENT_READER_END_WITH_ERROR;
  }
  while (got < max) {
    if (b->line) {
      long k = api_stream_read(b->line, buf + got, max - got);
      if (k < 0)
        break;
      got += (size_t)k;
      if (got == max)
        break; /* the line may go on */
      api_stream_free(b->line);
      b->line = NULL;
      batch_hold(b, -b->line_held);
      b->in_flight--;
      continue;
    }
    if (b->last) {
      size_t k = b->last_len - b->last_off;
      k = k < max - got ? k : max - got;
      memcpy(buf + got, b->last + b->last_off, k);
      b->last_off += k;
      got += k;
      break;
    }
    dispatch(b);
    int rc = next_line(b);
    if (rc < 0) {
      pthread_mutex_unlock(&b->mu);
      return MHD_CONTENT_READER_END_WITH_ERROR;
    }
    if (rc == 0)
      break;
  }
  ssize_t ret = (ssize_t)got;
  b->sent += got;
  if (got == 0 && b->last)
    ret = MHD_CONTENT_READER_END_OF_STREAM;
  else if (got == 0) {
    /* nothing to write until an item is done: item_done resumes */
    b->waiting = 1;
    MHD_suspend_connection(b->c);
  }
  pthread_mutex_unlock(&b->mu);
  return ret;
}

/* batch_read, gzipped: a piece of lines is deflated with Z_SYNC_FLUSH (its
 * bytes complete for the client at once); output that does not fit is kept
 * by zlib and given first on the next call. */
static ssize_t batch_read_gz(srv__batch *b, uint64_t pos, char *buf,
                             size_t max) {
  z_stream *zs = &b->zs;
  unsigned pend = 0;
  int bits = 0;
  zs->next_out = (Bytef *)buf;
  zs->avail_out = (uInt)max;
  deflatePending(zs, &pend, &bits);
  if (pend == 0 && !b->gz_finishing) {
    size_t in_max = max / 2 < SRV__STREAM_CHUNK ? max / 2 : SRV__STREAM_CHUNK;
    ssize_t n = batch_read(b, pos, b->gz_in, in_max > 0 ? in_max : 1);
    if (n == MHD_CONTENT_READER_END_WITH_ERROR)
      return n;
    if (n == MHD_CONTENT_READER_END_OF_STREAM)
      b->gz_finishing = 1;
    else if (n == 0)
      return 0; /* nothing ready: batch_read suspended the connection */
    else {
      zs->next_in = (Bytef *)b->gz_in;
      zs->avail_in = (uInt)n;
      b->sent -= (size_t)n; /* counted below as sent, compressed */
    }
  }
  if (b->gz_end)
    return MHD_CONTENT_READER_END_OF_STREAM;
  int rc = deflate(zs, b->gz_finishing ? Z_FINISH : Z_SYNC_FLUSH);
  if (rc == Z_STREAM_END)
    b->gz_end = 1;
  else if (rc != Z_OK && rc != Z_BUF_ERROR)
    return MHD_CONTENT_READER_END_WITH_ERROR;
  size_t got = max - zs->avail_out;
  b->sent += got;
  return got ? (ssize_t)got : MHD_CONTENT_READER_END_OF_STREAM;
}

static ssize_t batch_reader(void *cls, uint64_t pos, char *buf, size_t max) {
  srv__batch *b = cls;
  return b->gz ? batch_read_gz(b, pos, buf, max) : batch_read(b, pos, buf, max);
}

/* The response is done with the batch. */
static void batch_release(void *cls) {
  srv__batch *b = cls;
  pthread_mutex_lock(&b->mu);
  int last = --b->refs == 0;
  pthread_mutex_unlock(&b->mu);
  if (last)
    batch_free(b);
}

/* The request of a batch has completed (answered, or its client gone):
 * what is still in the pool stops, and nothing more is sent there.  The
 * bytes of the answer written, for the log. */
size_t srv__batch_detach(srv__batch *b) {
  pthread_mutex_lock(&b->mu);
  atomic_store(&b->gone, 1);
  atomic_store(&b->fd, -1);
  b->c = NULL;
  size_t sent = b->sent;
  pthread_mutex_unlock(&b->mu);
  return sent;
}

/* The parse of a body of up to --max-body grows with it (tens of
 * milliseconds for a megabyte): a job of the batch's client in the pool,
 * like a computation, so that the I/O thread only collects the bytes. */
void srv__batch_open(srv__req *r) {
  if (api_batch_open(r->buf, r->len, &r->d->cfg.lim, &r->ab, &r->ar) == 0)
    srv__hold(r->d, r, (long)api_batch_held(r->ab));
}

/* The body of a POST /batch is parsed (r->ab, which the batch takes over):
 * start the answer. */
enum MHD_Result srv__batch_start(struct srv_daemon *d, struct MHD_Connection *c,
                                 srv__req *r) {
  api_batch *ab = r->ab;
  r->ab = NULL;
  srv__hold(d, r, -(long)api_batch_held(ab)); /* the batch's from now on */
  srv__batch *b = calloc(1, sizeof *b);
  if (!b) {
    api_batch_free(ab);
    return srv__send_problem(c, r, API_P_OUT_OF_MEMORY, "out of memory", NULL,
                             0, NULL);
  }
  pthread_mutex_init(&b->mu, NULL);
  b->d = d;
  b->c = c;
  b->ab = ab;
  b->n = api_batch_size(ab);
  snprintf(b->key, sizeof b->key, "%s", r->key);
  atomic_store(&b->fd, r->cn ? r->cn->fd : -1);
  b->refs = 1; /* the response */
  b->t0 = r->t0;
  if (r->gzip && (b->gz_in = malloc(SRV__STREAM_CHUNK)) &&
      deflateInit2(&b->zs, SRV__GZIP_LEVEL, Z_DEFLATED, 15 + 16, 8,
                   Z_DEFAULT_STRATEGY) == Z_OK) {
    b->gz = 1;
    batch_hold(b, SRV__GZIP_STATE);
  }
  batch_hold(b, (long)api_batch_held(ab));
  struct MHD_Response *resp = MHD_create_response_from_callback(
      MHD_SIZE_UNKNOWN, SRV__STREAM_CHUNK, batch_reader, b, batch_release);
  if (!resp) {
    batch_free(b);
    return MHD_NO;
  }
  MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE,
                          "application/x-ndjson");
  MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, "Accept-Encoding");
  if (b->gz)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_ENCODING, "gzip");
  srv__common_headers(r, resp);
  r->batch = b;
  pthread_mutex_lock(&b->mu);
  dispatch(b);
  pthread_mutex_unlock(&b->mu);
  enum MHD_Result ok = MHD_queue_response(c, MHD_HTTP_OK, resp);
  MHD_destroy_response(resp);
  r->status = MHD_HTTP_OK;
  r->done = 1;
  return ok;
}
