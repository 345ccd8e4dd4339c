/*
 * store.h: the durable store of jobs (POST with Prefer: respond-async).
 *
 * A job is a request kept with its endpoint's path and body, cut by the api
 * into chunks (api_job_open); each chunk is computed on its own and its
 * result written here before it counts as done, so that a daemon killed and
 * started again on the same store, or another replica on it, computes only
 * the chunks not stored.  Chunks come in stages: a chunk may start once
 * every chunk of the stages before its own is stored.
 *
 * A replica claims a chunk with a lease (store_claim) and renews it while
 * it computes (store_renew); a lease not renewed expires and the chunk goes
 * to whoever claims next.  A result is stored only under a lease still held
 * (store_complete), so a chunk is stored once whatever replicas do.
 *
 * One interface, two backends, chosen by the URI's scheme:
 *   sqlite:PATH          libsqlite3, WAL; the embedded default
 *   postgresql://...     libpq; replicas share it (claims take
 *                        SELECT ... FOR UPDATE SKIP LOCKED)
 * Every function is thread-safe: a store holds one connection, used under
 * a mutex of its own for the whole of each call (threads of one daemon
 * wait for each other; replicas and other processes do not).
 * Times are seconds since the epoch (wall clock: replicas compare them).
 * Functions return 0 for done, STORE_NONE for "no such thing" where the
 * function says so, and STORE_ERROR when the store failed (unreachable,
 * full, read-only, corrupt): store_error() then tells why.
 */
#ifndef SS_SERVER_STORE_H
#define SS_SERVER_STORE_H

#include <stddef.h>

enum { STORE_NONE = 1, STORE_ERROR = -1 };

/** A job's id: 32 lowercase hex digits (128 random bits). */
#define STORE_ID_LEN 32

/** A job's status: OGC API - Processes' names (store_status_name). */
typedef enum store_status {
  STORE_ACCEPTED = 0, /**< no chunk claimed yet */
  STORE_RUNNING,      /**< a chunk claimed */
  STORE_SUCCESSFUL,   /**< every chunk stored */
  STORE_FAILED,       /**< a chunk failed: the job's problem says why */
  STORE_DISMISSED     /**< deleted by its client; its results are gone */
} store_status;

/** "accepted", "running", "successful", "failed", "dismissed". */
const char *store_status_name(store_status s);

/** What the store tells of a job. */
typedef struct store_job {
  char id[STORE_ID_LEN + 1];
  char path[32]; /**< its endpoint, e.g. "/map" */
  store_status status;
  double created, started, updated, finished; /**< 0: not yet */
  long chunks, chunks_done;
  long items, items_done; /**< the units progress is told in (cells,
                               batch items; 1 for a single answer) */
  char message[256];      /**< a failed job's reason, else "" */
} store_job;

/** One chunk of a job as it is submitted. */
typedef struct store_chunk {
  int stage;  /**< 0, 1, ...: starts once the stages before are stored */
  long items; /**< what it adds to items_done */
} store_chunk;

typedef struct store store;

/**
 * Open the store at @a uri ("sqlite:PATH" or "postgresql://..."), creating
 * its tables when they are not there.  0 and *s; or STORE_ERROR, *s NULL,
 * and the reason in @a why.
 */
int store_open(const char *uri, store **s, char *why, size_t n);
/** Close; NULL-safe. */
void store_close(store *s);
/** "sqlite" or "postgresql". */
const char *store_kind(const store *s);
/** Why the last call that returned STORE_ERROR on this thread failed. */
const char *store_error(const store *s);

/** Keep a new job (@a j: id, path, created; status accepted) with its
 *  request @a body and its @a n chunks.  0 or STORE_ERROR. */
int store_submit(store *s, const store_job *j, const char *body, size_t len,
                 const store_chunk *chunks, size_t n);
/** Job @a id into *out: 0, STORE_NONE or STORE_ERROR. */
int store_get(store *s, const char *id, store_job *out);
/** The request body of job @a id (malloc'd, NUL-terminated): 0,
 *  STORE_NONE or STORE_ERROR. */
int store_body(store *s, const char *id, char **body, size_t *len);
/** Jobs newest first: at most @a max from the @a offset-th, into @a out;
 *  *n the number written, *total the number there are.  0 or STORE_ERROR. */
int store_list(store *s, long offset, size_t max, store_job *out, size_t *n,
               long *total);

/**
 * Claim a chunk for @a owner (a replica's name) until @a now + @a lease: one
 * of a job accepted or running, not stored, whose earlier stages are all
 * stored, and unleased or whose lease ended before @a now; the oldest job
 * first.  The job becomes running.  0 with *id and *chunk; STORE_NONE when
 * there is none; STORE_ERROR.
 */
int store_claim(store *s, const char *owner, double now, double lease,
                char id[STORE_ID_LEN + 1], long *chunk);
/** Extend @a owner's lease on a chunk until @a until: 0; STORE_NONE when
 *  the lease is no longer its own (expired and taken, or the job was
 *  dismissed or failed); STORE_ERROR. */
int store_renew(store *s, const char *owner, const char *id, long chunk,
                double until);
/**
 * Store chunk @a chunk's result under @a owner's lease, counting it done
 * (and the job successful, finished at @a now, when it is the last): 0;
 * STORE_NONE when the lease is no longer its own (nothing is written);
 * STORE_ERROR.
 */
int store_complete(store *s, const char *owner, const char *id, long chunk,
                   const void *result, size_t len, double now);
/** Fail job @a id at @a now: its @a message and its answer, a problem with
 *  HTTP @a status and body @a problem: 0, STORE_NONE (no such job, or one
 *  already finished), STORE_ERROR. */
int store_fail(store *s, const char *id, const char *message, int status,
               const char *problem, size_t len, double now);
/** Chunk @a chunk's result (malloc'd) into *buf: 0; STORE_NONE when it is
 *  not stored (yet); STORE_ERROR. */
int store_result(store *s, const char *id, long chunk, char **buf, size_t *len);
/** A failed job's problem: its HTTP status and body (malloc'd): 0,
 *  STORE_NONE, STORE_ERROR. */
int store_problem(store *s, const char *id, int *status, char **body,
                  size_t *len);
/** Dismiss job @a id at @a now: status dismissed, its body, chunks and
 *  results deleted (the job's row stays until it expires): 0, STORE_NONE,
 *  STORE_ERROR. */
int store_dismiss(store *s, const char *id, double now);
/** The jobs by status (indexed by store_status) and the chunks waiting to
 *  be claimed or leased now (of jobs accepted or running, not stored), for
 *  the metrics.  0 or STORE_ERROR. */
int store_counts(store *s, long by_status[5], long *chunks_pending);
/** Delete the jobs finished (successful, failed, dismissed) before
 *  @a before; *n the number deleted.  0 or STORE_ERROR. */
int store_expire(store *s, double before, long *n);

#endif
