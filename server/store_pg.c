/*
 * store_pg.c: the job store in PostgreSQL (libpq), for replicas.
 *
 * Every replica opens its own connection to one database; they share the
 * jobs.  A claim picks its chunk with SELECT ... FOR UPDATE SKIP LOCKED,
 * marks its job running and leases it in one statement (one round trip,
 * where a transaction of a statement each took five), so two replicas
 * claiming at once take different chunks, and neither waits for the
 * other.  Counters of a job (chunks done) are updated in place, so
 * concurrent completions of one job's chunks add up.  One connection per
 * store, used under a mutex; a connection that broke is reset once at the
 * next call.  The tables are named stickslip_* (the database may hold
 * others), created on open under an advisory lock, so replicas starting
 * together do not race.
 */
#include <arpa/inet.h>
#include <libpq-fe.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "store_impl.h"

typedef struct pgs {
  PGconn *db;
  pthread_mutex_t lock;
} pgs;

#define SCHEMA_VERSION "1"
#define SCHEMA_LOCK "727270301" /* pg_advisory_xact_lock's key */

static const char SCHEMA[] =
    "BEGIN;"
    "SELECT pg_advisory_xact_lock(" SCHEMA_LOCK ");"
    "CREATE TABLE IF NOT EXISTS stickslip_meta(key text PRIMARY KEY,"
    " value text);"
    "CREATE TABLE IF NOT EXISTS stickslip_jobs("
    " n bigserial PRIMARY KEY, id text NOT NULL UNIQUE, path text NOT NULL,"
    " status int NOT NULL, created double precision NOT NULL,"
    " started double precision NOT NULL DEFAULT 0,"
    " updated double precision NOT NULL,"
    " finished double precision NOT NULL DEFAULT 0,"
    " chunks bigint NOT NULL, chunks_done bigint NOT NULL DEFAULT 0,"
    " items bigint NOT NULL, items_done bigint NOT NULL DEFAULT 0,"
    " message text NOT NULL DEFAULT '', body bytea,"
    " problem_status int NOT NULL DEFAULT 0, problem bytea);"
    "CREATE INDEX IF NOT EXISTS stickslip_jobs_active"
    " ON stickslip_jobs(status, n);"
    "CREATE TABLE IF NOT EXISTS stickslip_chunks("
    " job bigint NOT NULL REFERENCES stickslip_jobs(n) ON DELETE CASCADE,"
    " k bigint NOT NULL, stage int NOT NULL, items bigint NOT NULL,"
    " done int NOT NULL DEFAULT 0, owner text, lease double precision,"
    " packed int NOT NULL DEFAULT 0, result bytea, PRIMARY KEY(job, k));"
    "CREATE INDEX IF NOT EXISTS stickslip_chunks_open"
    " ON stickslip_chunks(job, stage, k) WHERE done = 0;"
    "INSERT INTO stickslip_meta VALUES('schema', '" SCHEMA_VERSION "')"
    " ON CONFLICT DO NOTHING;"
    "COMMIT;";

static int fail_pg(pgs *p, const char *what) {
  char msg[400];
  snprintf(msg, sizeof msg, "%s", PQerrorMessage(p->db));
  size_t n = strlen(msg);
  while (n && (msg[n - 1] == '\n' || msg[n - 1] == ' '))
    msg[--n] = 0;
  return store__fail("postgresql store: %s: %s", what, msg);
}

static void enter(pgs *p) {
  pthread_mutex_lock(&p->lock);
  if (PQstatus(p->db) != CONNECTION_OK)
    PQreset(p->db);
}

static void leave(pgs *p) { pthread_mutex_unlock(&p->lock); }

/* Run @a sql with text parameters (a NULL length array: all text; lens[i]
 * > 0 with binary[i]: bytes), results in @a binary_out format.  The
 * result, or NULL with the failure recorded. */
static PGresult *q(pgs *p, const char *what, const char *sql, int n,
                   const char *const *vals, const int *lens, const int *formats,
                   int binary_out) {
  PGresult *r =
      PQexecParams(p->db, sql, n, NULL, vals, lens, formats, binary_out);
  ExecStatusType s = PQresultStatus(r);
  if (s != PGRES_COMMAND_OK && s != PGRES_TUPLES_OK) {
    fail_pg(p, what);
    PQclear(r);
    return NULL;
  }
  return r;
}

/* A statement with text parameters whose rows do not matter: the number
 * of rows it changed, or STORE_ERROR. */
static long cmd(pgs *p, const char *what, const char *sql, int n,
                const char *const *vals) {
  PGresult *r = q(p, what, sql, n, vals, NULL, NULL, 0);
  if (!r)
    return STORE_ERROR;
  long changed = atol(PQcmdTuples(r));
  PQclear(r);
  return changed;
}

static int tx(pgs *p, const char *sql) {
  PGresult *r = PQexec(p->db, sql);
  int ok = PQresultStatus(r) == PGRES_COMMAND_OK;
  PQclear(r);
  return ok ? 0 : fail_pg(p, sql);
}

static int end(pgs *p, int rc) {
  if (rc)
    tx(p, "ROLLBACK");
  else if (tx(p, "COMMIT"))
    rc = STORE_ERROR;
  return rc;
}

/* Notices ("relation already exists, skipping") are not errors, and the
 * daemon's standard error is its log: libpq's are dropped. */
static void quiet(void *arg, const char *message) {
  (void)arg;
  (void)message;
}

int store__pg_open(const char *uri, void **b, char *why, size_t n) {
  *b = NULL;
  pgs *p = calloc(1, sizeof *p);
  if (!p) {
    snprintf(why, n, "out of memory");
    return STORE_ERROR;
  }
  /* Defaults a URI may override (dbname, expanded from the URI, comes
   * last): a connection attempt gives up after 5 s, and a server that stops
   * answering fails a call within about 20 s (unacknowledged data, or
   * keepalives unanswered) instead of hanging it. */
  static const char *const keys[] = {"connect_timeout",  "keepalives",
                                     "keepalives_idle",  "keepalives_interval",
                                     "keepalives_count", "tcp_user_timeout",
                                     "dbname",           NULL};
  const char *vals[] = {"5", "1", "10", "3", "3", "20000", uri, NULL};
  p->db = PQconnectdbParams(keys, vals, 1);
  PQsetNoticeProcessor(p->db, quiet, NULL);
  pthread_mutex_init(&p->lock, NULL);
  int rc = 0;
  if (PQstatus(p->db) != CONNECTION_OK) {
    rc = fail_pg(p, "connect");
  } else {
    PGresult *r = PQexec(p->db, SCHEMA);
    if (PQresultStatus(r) != PGRES_COMMAND_OK)
      rc = fail_pg(p, "create the tables");
    PQclear(r);
    if (rc)
      tx(p, "ROLLBACK");
  }
  if (!rc) {
    PGresult *r = q(p, "read the schema",
                    "SELECT value FROM stickslip_meta WHERE key = 'schema'", 0,
                    NULL, NULL, NULL, 0);
    if (!r)
      rc = STORE_ERROR;
    else if (PQntuples(r) != 1 ||
             strcmp(PQgetvalue(r, 0, 0), SCHEMA_VERSION) != 0)
      rc = store__fail("postgresql store: not a job store of schema %s",
                       SCHEMA_VERSION);
    PQclear(r);
  }
  if (rc) {
    snprintf(why, n, "%s", store_error(NULL));
    PQfinish(p->db);
    pthread_mutex_destroy(&p->lock);
    free(p);
    return STORE_ERROR;
  }
  *b = p;
  return 0;
}

static void pg_close(void *b) {
  pgs *p = b;
  if (!p)
    return;
  PQfinish(p->db);
  pthread_mutex_destroy(&p->lock);
  free(p);
}

/* Text of a number, for a parameter. */
typedef struct num {
  char s[40];
} num;

static num dbl(double v) {
  num x;
  snprintf(x.s, sizeof x.s, "%.17g", v);
  return x;
}

static num lng(long long v) {
  num x;
  snprintf(x.s, sizeof x.s, "%lld", v);
  return x;
}

/* The arrays of a submission as PostgreSQL array literals: "{0,0,1}". */
static char *array_of(const store_chunk *c, size_t n, int items) {
  size_t room = 2 + n * 22, at = 0;
  char *s = malloc(room);
  if (!s)
    return NULL;
  s[at++] = '{';
  for (size_t k = 0; k < n; k++)
    at += (size_t)snprintf(s + at, room - at, "%s%ld", k ? "," : "",
                           items ? c[k].items : (long)c[k].stage);
  s[at++] = '}';
  s[at] = 0;
  return s;
}

static int pg_submit(void *b, const store_job *j, const char *body, size_t len,
                     const store_chunk *chunks, size_t n) {
  pgs *p = b;
  long items = 0;
  for (size_t k = 0; k < n; k++)
    items += chunks[k].items;
  char *stages = array_of(chunks, n, 0), *its = array_of(chunks, n, 1);
  if (!stages || !its) {
    free(stages);
    free(its);
    return store__fail("out of memory submitting %zu chunks", n);
  }
  enter(p);
  int rc = tx(p, "BEGIN");
  num created = dbl(j->created), nc = lng((long long)n), ni = lng(items);
  const char *v[] = {j->id, j->path, created.s, nc.s, ni.s, body};
  int lens[] = {0, 0, 0, 0, 0, (int)len}, fmt[] = {0, 0, 0, 0, 0, 1};
  PGresult *r =
      rc || len > INT32_MAX
          ? NULL
          : q(p, "submit",
              "INSERT INTO stickslip_jobs(id, path, status, created, "
              "updated, chunks, items, body) VALUES($1, $2, 0, $3, $3, $4, "
              "$5, $6) RETURNING n",
              6, v, lens, fmt, 0);
  if (!rc && len > INT32_MAX)
    rc = store__fail("postgresql store: a body of %zu bytes", len);
  if (!rc && !r)
    rc = STORE_ERROR;
  if (!rc) {
    const char *w[] = {PQgetvalue(r, 0, 0), stages, its};
    if (cmd(p, "submit its chunks",
            "INSERT INTO stickslip_chunks(job, k, stage, items) "
            "SELECT $1, s.k - 1, s.stage, s.items FROM "
            "unnest($2::int[], $3::bigint[]) WITH ORDINALITY "
            "AS s(stage, items, k)",
            3, w) < 0)
      rc = STORE_ERROR;
  }
  PQclear(r);
  rc = end(p, rc);
  leave(p);
  free(stages);
  free(its);
  return rc;
}

#define JOB_COLUMNS                                                            \
  "id, path, status, created, started, updated, finished, chunks, "            \
  "chunks_done, items, items_done, message"

static void read_job(PGresult *r, int row, store_job *o) {
  memset(o, 0, sizeof *o);
  snprintf(o->id, sizeof o->id, "%s", PQgetvalue(r, row, 0));
  snprintf(o->path, sizeof o->path, "%s", PQgetvalue(r, row, 1));
  o->status = (store_status)atoi(PQgetvalue(r, row, 2));
  o->created = strtod(PQgetvalue(r, row, 3), NULL);
  o->started = strtod(PQgetvalue(r, row, 4), NULL);
  o->updated = strtod(PQgetvalue(r, row, 5), NULL);
  o->finished = strtod(PQgetvalue(r, row, 6), NULL);
  o->chunks = atol(PQgetvalue(r, row, 7));
  o->chunks_done = atol(PQgetvalue(r, row, 8));
  o->items = atol(PQgetvalue(r, row, 9));
  o->items_done = atol(PQgetvalue(r, row, 10));
  snprintf(o->message, sizeof o->message, "%s", PQgetvalue(r, row, 11));
}

static int pg_get(void *b, const char *id, store_job *out) {
  pgs *p = b;
  enter(p);
  const char *v[] = {id};
  PGresult *r = q(p, "read a job",
                  "SELECT " JOB_COLUMNS " FROM stickslip_jobs WHERE id = $1", 1,
                  v, NULL, NULL, 0);
  int rc = !r ? STORE_ERROR : PQntuples(r) ? 0 : STORE_NONE;
  if (!rc)
    read_job(r, 0, out);
  PQclear(r);
  leave(p);
  return rc;
}

/* Column 0 of the one row of @a r (binary), malloc'd and NUL-terminated:
 * 0, STORE_NONE (no row, or NULL), STORE_ERROR.  *extra: column 1, an
 * int4 in binary, when non-NULL. */
static int read_blob(PGresult *r, char **buf, size_t *len, int *extra) {
  if (!PQntuples(r) || PQgetisnull(r, 0, 0))
    return STORE_NONE;
  size_t n = (size_t)PQgetlength(r, 0, 0);
  char *out = malloc(n + 1);
  if (!out)
    return store__fail("out of memory reading %zu bytes", n);
  memcpy(out, PQgetvalue(r, 0, 0), n);
  out[n] = 0;
  *buf = out;
  *len = n;
  if (extra) {
    uint32_t v;
    memcpy(&v, PQgetvalue(r, 0, 1), sizeof v);
    *extra = (int)ntohl(v);
  }
  return 0;
}

/* The blob a query of one row gives (read_blob; @a sql run with the text
 * parameters @a v, binary results), in a call of its own: the store left. */
static int read_one(pgs *p, const char *what, const char *sql, int n,
                    const char *const *v, char **buf, size_t *len, int *extra) {
  PGresult *r = q(p, what, sql, n, v, NULL, NULL, 1);
  int rc = r ? read_blob(r, buf, len, extra) : STORE_ERROR;
  PQclear(r);
  leave(p);
  return rc;
}

static int pg_body(void *b, const char *id, char **body, size_t *len) {
  pgs *p = b;
  enter(p);
  const char *v[] = {id};
  return read_one(p, "read a body",
                  "SELECT body FROM stickslip_jobs WHERE id = $1", 1, v, body,
                  len, NULL);
}

static int pg_list(void *b, long offset, size_t max, store_job *out, size_t *n,
                   long *total) {
  pgs *p = b;
  *n = 0;
  *total = 0;
  enter(p);
  num lim = lng((long long)max), off = lng(offset);
  const char *v[] = {lim.s, off.s};
  PGresult *r = q(p, "list jobs",
                  "SELECT " JOB_COLUMNS ", count(*) OVER () FROM "
                  "stickslip_jobs ORDER BY n DESC LIMIT $1 OFFSET $2",
                  2, v, NULL, NULL, 0);
  int rc = r ? 0 : STORE_ERROR;
  for (int i = 0; r && i < PQntuples(r) && *n < max; i++) {
    read_job(r, i, &out[(*n)++]);
    *total = atol(PQgetvalue(r, i, 12));
  }
  PQclear(r);
  if (!rc && *n == 0) { /* past the end: the total alone */
    r = q(p, "count jobs", "SELECT count(*) FROM stickslip_jobs", 0, NULL, NULL,
          NULL, 0);
    if (r)
      *total = atol(PQgetvalue(r, 0, 0));
    else
      rc = STORE_ERROR;
    PQclear(r);
  }
  leave(p);
  return rc;
}

/* One statement, one round trip: the jobs accepted or running, oldest
 * first, and in each (LATERAL, one job after another until a chunk is
 * found: the jobs' ORDER BY keeps them from being merged into the outer
 * query, so the outer LIMIT stops there) the first chunk that can be
 * claimed at $1: of its lowest stage not stored (a later stage waits for
 * it), not stored, unleased or its lease ended, and not locked by another
 * replica's claim at this moment (SKIP LOCKED: it takes the next one, or
 * the next job's, instead of waiting).  Then the job becomes running, and
 * only if it still is accepted or running (another replica may have
 * finished it since the statement's snapshot) is the chunk leased to $2
 * until $3: the chunk's row is locked before the job's, as a completion
 * locks them.  The partial index stickslip_chunks_open (the chunks not
 * stored, in stage and k order) makes both the stage and the chunk its
 * first entries, however many chunks are stored: a scan of the job's
 * chunks took 6 ms a claim in a job of 5000. */
static const char CLAIM[] =
    "WITH c AS (SELECT j.n, x.k FROM (SELECT n FROM stickslip_jobs WHERE "
    "status IN (0, 1) ORDER BY n) j, LATERAL (SELECT k FROM stickslip_chunks "
    "WHERE job = j.n AND done = 0 AND stage = (SELECT min(stage) FROM "
    "stickslip_chunks WHERE job = j.n AND done = 0) AND (owner IS NULL OR "
    "lease < $1) ORDER BY stage, k LIMIT 1 FOR UPDATE SKIP LOCKED) x LIMIT 1), "
    "j AS (UPDATE stickslip_jobs SET status = 1, updated = $1, started = "
    "CASE WHEN started = 0 THEN $1 ELSE started END FROM c "
    "WHERE stickslip_jobs.n = c.n AND status IN (0, 1) RETURNING c.n, c.k, "
    "stickslip_jobs.id) "
    "UPDATE stickslip_chunks s SET owner = $2, lease = $3 FROM j "
    "WHERE s.job = j.n AND s.k = j.k RETURNING j.id, s.k";

/* A chunk of the oldest job accepted or running that has one to claim. */
static int pg_claim(void *b, const char *owner, double now, double lease,
                    char id[STORE_ID_LEN + 1], long *chunk) {
  pgs *p = b;
  enter(p);
  num t = dbl(now), until = dbl(now + lease);
  const char *v[] = {t.s, owner, until.s};
  PGresult *r = q(p, "claim", CLAIM, 3, v, NULL, NULL, 0);
  int rc = !r ? STORE_ERROR : PQntuples(r) ? 0 : STORE_NONE;
  if (!rc) {
    snprintf(id, STORE_ID_LEN + 1, "%s", PQgetvalue(r, 0, 0));
    *chunk = atol(PQgetvalue(r, 0, 1));
  }
  PQclear(r);
  leave(p);
  return rc;
}

#define HELD                                                                   \
  "job = (SELECT n FROM stickslip_jobs WHERE id = $1 AND status IN "           \
  "(0, 1)) AND k = $2 AND owner = $3 AND done = 0"

static int pg_renew(void *b, const char *owner, const char *id, long chunk,
                    double until) {
  pgs *p = b;
  enter(p);
  num k = lng(chunk), u = dbl(until);
  const char *v[] = {id, k.s, owner, u.s};
  long changed = cmd(
      p, "renew", "UPDATE stickslip_chunks SET lease = $4 WHERE " HELD, 4, v);
  leave(p);
  return changed < 0 ? STORE_ERROR : changed ? 0 : STORE_NONE;
}

static int pg_complete(void *b, const char *owner, const char *id, long chunk,
                       const void *result, size_t len, int packed, double now) {
  pgs *p = b;
  if (len > INT32_MAX)
    return store__fail("postgresql store: a result of %zu bytes", len);
  enter(p);
  int rc = tx(p, "BEGIN");
  num k = lng(chunk), pk = lng(packed), t = dbl(now);
  const char *v[] = {id, k.s, owner, pk.s, result ? result : ""};
  int lens[] = {0, 0, 0, 0, (int)len}, fmt[] = {0, 0, 0, 0, 1};
  PGresult *r = rc ? NULL
                   : q(p, "store a result",
                       "UPDATE stickslip_chunks SET done = 1, owner = NULL, "
                       "lease = NULL, packed = $4, result = $5 WHERE " HELD
                       " RETURNING items",
                       5, v, lens, fmt, 0);
  if (!rc && !r)
    rc = STORE_ERROR;
  if (!rc && PQntuples(r) == 0)
    rc = STORE_NONE;
  if (!rc) {
    const char *w[] = {id, PQgetvalue(r, 0, 0), t.s};
    if (cmd(p, "count a result",
            "UPDATE stickslip_jobs SET chunks_done = chunks_done + 1, "
            "items_done = items_done + $2, updated = $3, status = CASE WHEN "
            "chunks_done + 1 = chunks THEN 2 ELSE status END, finished = "
            "CASE WHEN chunks_done + 1 = chunks THEN $3 ELSE finished END "
            "WHERE id = $1",
            3, w) < 0)
      rc = STORE_ERROR;
  }
  PQclear(r);
  rc = end(p, rc);
  leave(p);
  return rc;
}

/* Lock the chunks of job @a id, in k order, before its row is written: a
 * claim or a completion locks its chunk, then the job's row, so that
 * taking the row first here would let each wait for the other (a deadlock
 * that PostgreSQL breaks by failing one of them). */
static int lock_chunks(pgs *p, const char *id) {
  const char *v[] = {id};
  return cmd(p, "lock the chunks",
             "SELECT 1 FROM stickslip_chunks WHERE job = (SELECT n FROM "
             "stickslip_jobs WHERE id = $1) ORDER BY k FOR UPDATE",
             1, v) < 0
             ? STORE_ERROR
             : 0;
}

static int pg_fail(void *b, const char *id, const char *message, int status,
                   const char *problem, size_t len, double now) {
  pgs *p = b;
  if (len > INT32_MAX)
    return store__fail("postgresql store: a problem of %zu bytes", len);
  enter(p);
  int rc = tx(p, "BEGIN");
  num st = lng(status), t = dbl(now);
  const char *v[] = {id, message ? message : "", st.s, problem ? problem : "",
                     t.s};
  int lens[] = {0, 0, 0, (int)len, 0}, fmt[] = {0, 0, 0, 1, 0};
  if (!rc)
    rc = lock_chunks(p, id);
  PGresult *r = rc ? NULL
                   : q(p, "fail a job",
                       "UPDATE stickslip_jobs SET status = 3, message = $2, "
                       "problem_status = $3, problem = $4, updated = $5, "
                       "finished = $5 WHERE id = $1 AND status IN (0, 1) "
                       "RETURNING n",
                       5, v, lens, fmt, 0);
  if (!rc && !r)
    rc = STORE_ERROR;
  if (!rc && PQntuples(r) == 0)
    rc = STORE_NONE;
  if (!rc) {
    /* a failed job's answer is its problem: its chunks are of no use */
    const char *w[] = {PQgetvalue(r, 0, 0)};
    if (cmd(p, "fail a job", "DELETE FROM stickslip_chunks WHERE job = $1", 1,
            w) < 0)
      rc = STORE_ERROR;
  }
  PQclear(r);
  rc = end(p, rc);
  leave(p);
  return rc;
}

static int pg_result(void *b, const char *id, long chunk, char **buf,
                     size_t *len, int *packed) {
  pgs *p = b;
  enter(p);
  num k = lng(chunk);
  const char *v[] = {id, k.s};
  return read_one(p, "read a result",
                  "SELECT result, packed FROM stickslip_chunks WHERE job = "
                  "(SELECT n FROM stickslip_jobs WHERE id = $1) AND k = $2 "
                  "AND done = 1",
                  2, v, buf, len, packed);
}

static int pg_problem(void *b, const char *id, int *status, char **body,
                      size_t *len) {
  pgs *p = b;
  enter(p);
  const char *v[] = {id};
  return read_one(p, "read a problem",
                  "SELECT problem, problem_status FROM stickslip_jobs "
                  "WHERE id = $1 AND status = 3",
                  1, v, body, len, status);
}

static int pg_dismiss(void *b, const char *id, double now) {
  pgs *p = b;
  enter(p);
  int rc = tx(p, "BEGIN");
  num t = dbl(now);
  const char *v[] = {id, t.s};
  if (!rc)
    rc = lock_chunks(p, id);
  PGresult *r =
      rc ? NULL
         : q(p, "dismiss",
             "UPDATE stickslip_jobs SET status = 4, body = NULL, problem = "
             "NULL, updated = $2, finished = CASE WHEN finished = 0 THEN $2 "
             "ELSE finished END WHERE id = $1 AND status != 4 RETURNING n",
             2, v, NULL, NULL, 0);
  if (!rc && !r)
    rc = STORE_ERROR;
  if (!rc && PQntuples(r) == 0)
    rc = STORE_NONE;
  if (!rc) {
    const char *w[] = {PQgetvalue(r, 0, 0)};
    if (cmd(p, "dismiss", "DELETE FROM stickslip_chunks WHERE job = $1", 1, w) <
        0)
      rc = STORE_ERROR;
  }
  PQclear(r);
  rc = end(p, rc);
  leave(p);
  return rc;
}

static int pg_counts(void *b, long by_status[5], long *chunks_pending) {
  pgs *p = b;
  for (int i = 0; i < 5; i++)
    by_status[i] = 0;
  *chunks_pending = 0;
  enter(p);
  PGresult *r = q(p, "count jobs",
                  "SELECT status, count(*) FROM stickslip_jobs GROUP BY "
                  "status UNION ALL SELECT -1, count(*) FROM "
                  "stickslip_chunks c JOIN stickslip_jobs j ON j.n = c.job "
                  "WHERE j.status IN (0, 1) AND c.done = 0",
                  0, NULL, NULL, NULL, 0);
  int rc = r ? 0 : STORE_ERROR;
  for (int i = 0; r && i < PQntuples(r); i++) {
    int s = atoi(PQgetvalue(r, i, 0));
    long c = atol(PQgetvalue(r, i, 1));
    if (s == -1)
      *chunks_pending = c;
    else if (s >= 0 && s < 5)
      by_status[s] = c;
  }
  PQclear(r);
  leave(p);
  return rc;
}

static int pg_expire(void *b, double before, long *n) {
  pgs *p = b;
  enter(p);
  num t = dbl(before);
  const char *v[] = {t.s};
  long changed = cmd(p, "expire",
                     "DELETE FROM stickslip_jobs WHERE status >= 2 AND "
                     "finished < $1",
                     1, v);
  leave(p);
  *n = changed > 0 ? changed : 0;
  return changed < 0 ? STORE_ERROR : 0;
}

const store_ops store__pg_ops = {
    .kind = "postgresql",
    .close = pg_close,
    .submit = pg_submit,
    .get = pg_get,
    .body = pg_body,
    .list = pg_list,
    .claim = pg_claim,
    .renew = pg_renew,
    .complete = pg_complete,
    .fail = pg_fail,
    .result = pg_result,
    .problem = pg_problem,
    .dismiss = pg_dismiss,
    .counts = pg_counts,
    .expire = pg_expire,
};
