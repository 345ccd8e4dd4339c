/*
 * batch.c: POST /batch: its body parsed and its items computed in the
 * pool, its answer streamed a line per item as each is done.
 *
 * The body is parsed on a worker (srv__batch_open, a job of the batch's
 * client), and the I/O thread starts the answer when the pool resumes the
 * request with the items (srv__batch_start).
 * A batch's answer is one chunked response whose lines are written as its
 * items are done.  Its items are computed by at most batch_parallel
 * runners, jobs of the pool in the queue of the batch's client like any
 * request.  A runner takes the batch's next items in ranges for a slice of
 * time (RUN_SLICE), writes a range's lines into the batch's buffer of lines
 * at once, and goes back to the end of its client's queue, so that the
 * client's other requests, and other clients, get their turn between runs
 * as they would between requests.  The I/O thread is woken for a run's
 * first lines, when BATCH_WAKE bytes of lines are ready, and at the run's
 * end, not once per item.  An item costs about 10 us of
 * computing: a hand-off to the pool and back for each (two thread wake-ups,
 * a job, a stream) cost ten times that.  The buffer holds at most
 * BATCH_BUFFER bytes of lines not yet written (a runner takes no item beyond
 * that; the lines being written restart the runners), so a batch holds
 * little whatever its client reads.  When no line is ready the response's
 * reader suspends the connection, and a runner resumes it.  The reader
 * never waits for a runner's hold of the batch: a runner descheduled while
 * it holds it would stop the I/O thread, and every connection, for a time
 * slice (batch_read).  So a runner resumes the connection only once it has
 * let go of the batch: the I/O thread it wakes may take its processor at
 * once, and, finding the batch held, would suspend again, to be resumed
 * again (on 2 cores that ping-pong cost 3 context switches an item).  When
 * the client goes away the runners that wait are dropped and the one that
 * runs is told to stop, as for any request.
 */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <zlib.h>

#include "internal.h"

/* A run takes items until it has computed this long (and at least one):
 * others wait at most about this long for a worker a batch holds, and the
 * run's hand-offs cost a few microseconds in it.  A slice of 1 ms instead
 * cost a batch item 1 us more of the daemon's CPU (23.9 against 22.8 us,
 * medians of 5 alternating rounds): each run's end and start is a hand-off
 * through the pool and a wake-up of the I/O thread. */
#define RUN_SLICE 4e-3
/* The most items a run claims at once: its lines are put in the batch's
 * buffer together, and the batch held once for them. */
#define RUN_RANGE 16
/* Lines not yet written that stop the runners: four stream chunks (of a
 * client that does not read, the batch then holds about this much, not
 * answers; with one chunk, runners stopped and were restarted every 16
 * lines of 2 KB). */
#define BATCH_BUFFER (4 * SRV__STREAM_CHUNK)
/* Lines ready that wake the I/O thread in the middle of a run: two of
 * what the response's reader takes at a time, written in one wake-up (one
 * chunk cost 0.9 us an item more, 22.7 against 21.8 us: each wake-up of the
 * I/O thread on 2 cores takes a processor from a runner). */
#define BATCH_WAKE (2 * SRV__STREAM_CHUNK)

typedef struct runner {
  srv_job job; /* first: a job is its runner */
  srv__batch *b;
  int in_pool;
  char *text; /* the line being made, reused from item to item */
  size_t len, cap;
} runner;

/* A line that is a stream (an answer larger than --stream-above). */
typedef struct sline {
  api_stream *s;
  long held;
  struct sline *next;
} sline;

struct srv__batch {
  pthread_mutex_t mu;
  struct srv_daemon *d;
  /* NULL once the request has completed; set to NULL under both locks,
   * resumed under cmu alone (batch_resume) */
  struct MHD_Connection *c;
  pthread_mutex_t cmu;
  api_batch *ab;
  char key[SRV_CLIENT_KEY];
  atomic_int fd;   /* of the connection; -1 once it has completed */
  atomic_int gone; /* the client went away: no more items */
  size_t n, next;  /* items, and the next one to compute */
  runner *run;     /* batch_parallel of them */
  unsigned n_run, in_pool;
  size_t ok, failed;
  int broken; /* a line could not be made: out of memory */
  char *out;  /* whole lines not yet written */
  size_t out_len, out_off, out_cap;
  sline *streams, *streams_tail;
  api_stream *line; /* the stream line being written */
  long line_held;
  char *last; /* the last line, once every item's line is written */
  size_t last_len, last_off;
  int waiting; /* the connection is suspended until a line is ready */
  /* the reader found b->mu taken and suspended the connection: the runner
   * that lets go of it resumes it (runner_unlock) */
  atomic_int kick;
  atomic_int refs; /* the response, and each runner in the pool */
  long held;       /* bytes counted against the memory budget */
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
  while (b->streams) {
    sline *l = b->streams;
    b->streams = l->next;
    api_stream_free(l->s);
    free(l);
  }
  for (unsigned k = 0; k < b->n_run; k++)
    free(b->run[k].text);
  free(b->run);
  free(b->out);
  api_stream_free(b->line);
  free(b->last);
  api_batch_free(b->ab);
  srv__held(b->d, b->key, -b->held);
  pthread_mutex_destroy(&b->cmu);
  pthread_mutex_destroy(&b->mu);
  free(b);
}

static int batch_gone(srv__batch *b) {
  return atomic_load(&b->gone) || srv__peer_closed(atomic_load(&b->fd));
}

static int runner_gone(srv_job *j) { return batch_gone(((runner *)j)->b); }

/* Lines are waiting to be written (under b->mu). */
static int lines_held(const srv__batch *b) {
  return b->out_len > b->out_off || b->streams || b->line;
}

/* The bytes of the buffer already written given back, once they are as
 * many as those left (so that a buffer its reader never empties does not
 * grow, and each byte is moved at most once on average). */
static void out_compact(srv__batch *b) {
  if (b->out_off == 0 || b->out_off < b->out_len - b->out_off)
    return;
  memmove(b->out, b->out + b->out_off, b->out_len - b->out_off);
  batch_hold(b, -(long)b->out_off);
  b->out_len -= b->out_off;
  b->out_off = 0;
}

/* Append @a len bytes of whole lines to the buffer (under b->mu); 0, or -1
 * when out of memory. */
static int out_put(srv__batch *b, const char *text, size_t len) {
  out_compact(b);
  if (b->out_len + len > b->out_cap) {
    /* at once the room a full buffer needs with a line beyond it */
    size_t cap = b->out_cap ? 2 * b->out_cap : BATCH_BUFFER + BATCH_BUFFER / 2;
    while (cap < b->out_len + len)
      cap *= 2;
    char *p = realloc(b->out, cap);
    if (!p)
      return -1;
    b->out = p;
    b->out_cap = cap;
  }
  memcpy(b->out + b->out_len, text, len);
  b->out_len += len;
  batch_hold(b, (long)len);
  return 0;
}

/* The line of item @a i, whose answer is @a ar (consumed), appended to
 * text (*buf, *len, *cap), or as a stream into *s when the answer is one;
 * 0, or -1 when out of memory. */
static int line_of(srv__batch *b, size_t i, api_response *ar, char **buf,
                   size_t *len, size_t *cap, api_stream **s, size_t *held) {
  *s = NULL;
  int put = api_batch_line_put(b->ab, i, ar, buf, len, cap);
  if (put == 0 && !(*s = api_batch_line(b->ab, i, ar, held)))
    return -1;
  return put < 0 ? -1 : 0;
}

/* Item @a i's line is made (under b->mu): counted, and the stream @a s, if
 * any, queued; @a rc -1: it could not be made. */
static void line_made(srv__batch *b, size_t i, int status, int rc,
                      api_stream *s, size_t held) {
  if (status == 200)
    b->ok++;
  else
    b->failed++;
  srv_metrics_batch_item(b->d->metrics, api_batch_endpoint(b->ab, i), status);
  if (rc < 0) {
    b->broken = 1;
    return;
  }
  if (!s)
    return;
  sline *l = malloc(sizeof *l);
  if (!l) {
    api_stream_free(s);
    b->broken = 1;
    return;
  }
  *l = (sline){s, (long)held, NULL};
  if (b->streams_tail)
    b->streams_tail->next = l;
  else
    b->streams = l;
  b->streams_tail = l;
  batch_hold(b, (long)held);
}

/* The next item answered at once with @a ar, without the pool (under
 * b->mu). */
static void item_now(srv__batch *b, api_response *ar) {
  out_compact(b);
  size_t i = b->next++, before = b->out_len, held = 0;
  int status = ar->status;
  api_stream *s;
  int rc = line_of(b, i, ar, &b->out, &b->out_len, &b->out_cap, &s, &held);
  batch_hold(b, (long)(b->out_len - before));
  line_made(b, i, status, rc, s, held);
}

static void item_problem(srv__batch *b, api_problem_kind kind,
                         const char *detail) {
  api_response ar;
  api_problem(&ar, kind, detail, NULL, NULL, 0);
  item_now(b, &ar);
}

/* The next items for runner @a ru, at most @a most of them, from *i on,
 * their count in *n (under b->mu): 1 to compute them, 2 to answer one with
 * the budget's 503, 0 to end the run. */
static int claim(srv__batch *b, runner *ru, size_t most, size_t *i, size_t *n) {
  struct srv_daemon *d = b->d;
  if (atomic_load(&b->gone) || atomic_load(&ru->job.cancel) ||
      atomic_load(&d->draining) || b->broken || b->next == b->n ||
      b->out_len - b->out_off >= BATCH_BUFFER)
    return 0;
  int rc = 1;
  if (srv__over_budget(d, b->key)) {
    /* the lines held, or another runner's, will give bytes back */
    if (lines_held(b) || b->in_pool > 1)
      return 0;
    rc = 2;
    most = 1;
  }
  *i = b->next;
  *n = b->n - b->next < most ? b->n - b->next : most;
  b->next += *n;
  return rc;
}

/* The connection, suspended until lines are ready, resumed by a runner
 * that does not hold b->mu: the I/O thread it wakes may take the runner's
 * processor at once, and would find b->mu still held (batch_read).  cmu
 * keeps the connection from completing in between (srv__batch_detach). */
static void batch_resume(srv__batch *b) {
  pthread_mutex_lock(&b->cmu);
  if (b->c)
    MHD_resume_connection(b->c);
  pthread_mutex_unlock(&b->cmu);
}

/* b->mu let go by a runner, which holds a reference to the batch: the
 * reader, if it found the lock taken (batch_read), resumed, once the lock
 * is let go.  The flag is read after the lock is let go, so that a reader
 * that sets it after a runner's last look finds the lock free on its
 * second try. */
static void runner_unlock(srv__batch *b) {
  pthread_mutex_unlock(&b->mu);
  while (atomic_load(&b->kick)) {
    int resume = 0;
    pthread_mutex_lock(&b->mu);
    if (atomic_exchange(&b->kick, 0) && b->c)
      resume = 1;
    pthread_mutex_unlock(&b->mu);
    if (resume)
      batch_resume(b);
  }
}

/* An item of a run, computed, its line not yet counted. */
typedef struct item_done {
  int status, rc;
  api_stream *s; /* its line when it is a stream */
  size_t held;
} item_done;

/* How many items a run claims at once, after the first (claimed alone, so
 * that its line goes out while the others compute, which may be long). */
static size_t run_claims(double t0, double now, size_t done) {
  double left = RUN_SLICE - (now - t0), per = (now - t0) / (double)done;
  if (left <= 0)
    return 0;
  if (per <= 0 || left / per >= RUN_RANGE)
    return RUN_RANGE;
  return left / per >= 1 ? (size_t)(left / per) : 1;
}

/* A run: the batch's next items, computed in ranges whose lines are put in
 * the batch's buffer together, until the slice is used up or no item may be
 * taken.  The batch is held once a range: its lines put and the next range
 * claimed together; a range is as many items as the run's own pace fits in
 * what is left of its slice, so that a range of long items is one item. */
static void runner_run(srv_job *j) {
  runner *ru = (runner *)j;
  srv__batch *b = ru->b;
  struct srv_daemon *d = b->d;
  api_server_info info = srv__server_info(d, j);
  double t0 = srv__now();
  int woke = 0;
  size_t i, n, done = 0;
  pthread_mutex_lock(&b->mu);
  int what = claim(b, ru, 1, &i, &n);
  runner_unlock(b);
  while (what) {
    item_done it[RUN_RANGE];
    ru->len = 0;
    for (size_t k = 0; k < n; k++) {
      api_response ar;
      if (what == 2)
        srv__budget_problem(d, b->key, &ar);
      else
        api_batch_run(b->ab, i + k, &d->cfg.lim, &info, &ar);
      it[k].status = ar.status;
      it[k].held = 0;
      it[k].rc = line_of(b, i + k, &ar, &ru->text, &ru->len, &ru->cap, &it[k].s,
                         &it[k].held);
    }
    done += n;
    size_t most = run_claims(t0, srv__now(), done);
    pthread_mutex_lock(&b->mu);
    int put = ru->len ? out_put(b, ru->text, ru->len) : 0;
    for (size_t k = 0; k < n; k++)
      line_made(b, i + k, it[k].status, put < 0 ? -1 : it[k].rc, it[k].s,
                it[k].held);
    size_t pending = b->out_len - b->out_off;
    int wake = 0;
    if (b->waiting && b->c && (pending >= BATCH_WAKE || !woke)) {
      /* the first lines of the run go out while the next items compute
       * (which may be long), the others when there are enough of them to
       * be worth a wake-up of the I/O thread, or at the run's end */
      b->waiting = 0;
      woke = 1;
      wake = 1;
    }
    /* no more lines, at the range's pace, than the buffer has room for */
    size_t line = ru->len / n;
    if (line && pending < BATCH_BUFFER &&
        most > (BATCH_BUFFER - pending) / line)
      most = (BATCH_BUFFER - pending) / line + 1;
    what = most ? claim(b, ru, most, &i, &n) : 0;
    runner_unlock(b);
    if (wake)
      batch_resume(b);
    if (ru->cap > BATCH_BUFFER) { /* a large line: its room not kept */
      free(ru->text);
      ru->text = NULL;
      ru->cap = 0;
    }
  }
}

static void dispatch(srv__batch *b);

/* A run is over: more runs while items are left and the buffer has room;
 * the I/O thread woken for the lines written. */
static void runner_done(srv_job *j) {
  runner *ru = (runner *)j;
  srv__batch *b = ru->b;
  pthread_mutex_lock(&b->mu);
  ru->in_pool = 0;
  b->in_pool--;
  if (j->state == SRV_JOB_CANCELLED && batch_gone(b)) {
    atomic_store(&b->gone, 1);
    srv_metrics_cancelled(b->d->metrics);
  } else {
    if (j->state == SRV_JOB_REFUSED && b->next < b->n)
      item_problem(b, API_P_SHUTTING_DOWN,
                   "the server is shutting down; retry on another replica or "
                   "later");
    dispatch(b);
  }
  int resume = b->waiting && b->c;
  if (resume)
    b->waiting = 0;
  runner_unlock(b);
  if (resume)
    batch_resume(b);
  /* the runner's reference, dropped without the lock, which the reader
   * may be trying for */
  if (atomic_fetch_sub(&b->refs, 1) == 1)
    batch_free(b);
}

static const srv_job_ops RUNNER_JOB = {NULL, runner_run, runner_done,
                                       runner_gone};

/* Send idle runners to the pool while items are left and the buffer has
 * room (under b->mu).  When the client's queue is full or the memory
 * budget (or the client's share of it) is spent, wait for a runner or the
 * lines held; with neither, the next item is answered 503 as a request
 * would be. */
static void dispatch(srv__batch *b) {
  struct srv_daemon *d = b->d;
  while (!atomic_load(&b->gone) && !b->broken && b->next < b->n &&
         b->out_len - b->out_off < BATCH_BUFFER) {
    if (atomic_load(&d->draining)) {
      item_problem(b, API_P_SHUTTING_DOWN, "the server is shutting down");
      continue;
    }
    runner *ru = NULL;
    for (unsigned k = 0; k < b->n_run && !ru; k++)
      if (!b->run[k].in_pool)
        ru = &b->run[k];
    if (!ru)
      return;
    int busy = lines_held(b) || b->in_pool > 0, rc;
    if (srv__over_budget(d, b->key)) {
      if (busy)
        return;
      api_response ar;
      srv__budget_problem(d, b->key, &ar);
      item_now(b, &ar);
    } else if ((rc = srv_pool_submit(d->pool, &ru->job, b->key)) != 0) {
      if (rc == SRV_POOL_FULL && busy)
        return;
      if (rc == SRV_POOL_FULL)
        srv_metrics_busy(d->metrics);
      item_problem(b,
                   rc == SRV_POOL_FULL    ? API_P_OVERLOADED
                   : rc == SRV_POOL_NOMEM ? API_P_OUT_OF_MEMORY
                                          : API_P_SHUTTING_DOWN,
                   rc == SRV_POOL_FULL ? "this client's queue is full; retry "
                                         "the item after a second"
                                       : "the item could not be queued");
    } else {
      ru->in_pool = 1;
      b->in_pool++;
      atomic_fetch_add(&b->refs, 1);
    }
  }
}

/* The last line, once every item's line is written (under b->mu); 0 when
 * it is not time yet, -1 when out of memory. */
static int last_line(srv__batch *b) {
  if (b->next < b->n || b->in_pool > 0 || lines_held(b) || b->last)
    return 0;
  api_response done;
  api_batch_done(b->ok, b->failed, srv__now() - b->t0, &done);
  b->last = done.body;
  b->last_len = done.len;
  return b->last ? 1 : -1;
}

/* The reader of a batch's response, on the I/O thread: the stream line
 * begun, the buffer's lines, the next stream line, the last line. */
static ssize_t batch_read(void *cls, uint64_t pos, char *buf, size_t max) {
  srv__batch *b = cls;
  size_t got = 0;
  (void)pos;
  if (pthread_mutex_trylock(&b->mu) != 0) {
    /* A runner holds the batch, and a worker may be descheduled while it
     * does (a time slice, milliseconds, on a loaded machine): the I/O
     * thread, which every connection waits for, does not wait for it.  The
     * connection is suspended until the runner lets go (runner_unlock);
     * when the lock is free by the second try, the runner let go before it
     * could see the flag, and the reader resumes itself. */
    atomic_store(&b->kick, 1);
    MHD_suspend_connection(b->c);
    if (pthread_mutex_trylock(&b->mu) == 0) {
      if (atomic_exchange(&b->kick, 0))
        MHD_resume_connection(b->c);
      pthread_mutex_unlock(&b->mu);
    }
    return 0;
  }
  if (atomic_load(&b->gone) || b->broken) {
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
      continue;
    }
    if (b->out_off < b->out_len) {
      size_t k = b->out_len - b->out_off;
      k = k < max - got ? k : max - got;
      memcpy(buf + got, b->out + b->out_off, k);
      b->out_off += k;
      got += k;
      if (b->out_off == b->out_len) {
        batch_hold(b, -(long)b->out_len);
        b->out_off = b->out_len = 0;
      }
      continue;
    }
    if (b->streams) {
      sline *l = b->streams;
      if (!(b->streams = l->next))
        b->streams_tail = NULL;
      b->line = l->s;
      b->line_held = l->held;
      free(l);
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
    if (lines_held(b))
      continue; /* answered at once by dispatch */
    int rc = last_line(b);
    if (rc < 0 || b->broken) {
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
    /* nothing to write until a run ends: runner_done resumes */
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
  if (atomic_fetch_sub(&b->refs, 1) == 1)
    batch_free(b);
}

/* The request of a batch has completed (answered, or its client gone):
 * what is still in the pool stops, and nothing more is sent there.  The
 * bytes of the answer written, for the log. */
size_t srv__batch_detach(srv__batch *b) {
  pthread_mutex_lock(&b->mu);
  atomic_store(&b->gone, 1);
  atomic_store(&b->fd, -1);
  pthread_mutex_lock(&b->cmu);
  b->c = NULL;
  pthread_mutex_unlock(&b->cmu);
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
  pthread_mutex_init(&b->cmu, NULL);
  b->d = d;
  b->c = c;
  b->ab = ab;
  b->n = api_batch_size(ab);
  snprintf(b->key, sizeof b->key, "%s", r->key);
  atomic_store(&b->fd, r->cn ? r->cn->fd : -1);
  b->n_run =
      d->cfg.batch_parallel < b->n ? d->cfg.batch_parallel : (unsigned)b->n;
  if (!(b->run = calloc(b->n_run, sizeof *b->run))) {
    pthread_mutex_destroy(&b->cmu);
    pthread_mutex_destroy(&b->mu);
    free(b);
    api_batch_free(ab);
    return srv__send_problem(c, r, API_P_OUT_OF_MEMORY, "out of memory", NULL,
                             0, NULL);
  }
  for (unsigned k = 0; k < b->n_run; k++) {
    b->run[k].job.ops = &RUNNER_JOB;
    b->run[k].job.kind = (unsigned)r->ep; /* counted as the /batch's */
    b->run[k].b = b;
  }
  atomic_init(&b->refs, 1); /* the response */
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
