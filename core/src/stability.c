/*
 * stability.c: the Poincare map on the section Sigma0 (4.2) and its
 * Jacobian (section 4).
 *
 * The paper composes J = Jf Jc Jb from the phase matrices with corrections
 * for the perturbed switching times; its printed entries carry typos, so the
 * composition is derived here for any phase sequence.  A perturbation dZ of
 * the state at the start of phase k is carried by the phase map A_k(tau_k)
 * and the switching time moves by dtau = -n.A dZ / (n.f), where f is the
 * vector field at the end of the phase and n the gradient of its switching
 * function (e4 for x2' = V; chi (e2 - e1) for chi(x2-x1) = +-ur).  The state
 * at the perturbed switching instant is therefore
 *   dZ' = (I - f n^T / (n.f)) A_k dZ.
 * A perturbation on Sigma0 is dZ0 = (x, x, v, 0) (4.3); after the last
 * stick, n.dZ = 0 puts it back on Sigma0 and (x_f, v_f) = (dz1, dz1').
 */
#include <math.h>
#include <string.h>

#include "linalg.h"
#include "simulate.h"
#include "stability.h"

/* Room for the phases of one return to Sigma0 while searching. */
#define MAP_HORIZON 1e5

static void eig2(const double J[2][2], double re[2], double im[2]) {
  double tr = J[0][0] + J[1][1];
  double det = J[0][0] * J[1][1] - J[0][1] * J[1][0];
  double h = 0.5 * tr, disc = h * h - det;
  if (disc >= 0) {
    double r = sqrt(disc);
    /* larger magnitude first, the other from the product (no cancellation) */
    double l1 = h >= 0 ? h + r : h - r;
    double l2 = l1 != 0 ? det / l1 : 0;
    re[0] = l1;
    re[1] = l2;
    im[0] = im[1] = 0;
  } else {
    re[0] = re[1] = h;
    im[0] = sqrt(-disc);
    im[1] = -im[0];
  }
}

int ss__returns_start(ss__returns *r, const ss_model *m, const double s[2]) {
  const ss_params *p = &m->p;
  double z[4] = {s[0], s[0] + (p->ur - p->us) / p->chi, s[1], p->V}, x[4];
  ss_z_to_x(m, z, x);
  r->t_last = 0;
  r->np = 0;
  r->poll = NULL;
  return ss__sim_init_mode(&r->sim, m, 0, x, SS_MODE_SLIP, NULL);
}

int ss__returns_next(ss__returns *r, size_t *events_left, double out[2],
                     ss_mode *modes, double *durations) {
  ss_event ev;
  while (*events_left > 0) {
    if (ss__poll_tick(r->poll))
      return SS_ECANCELED;
    (*events_left)--;
    double t_stop = ss_sim_time(&r->sim) + MAP_HORIZON;
    ss_mode cur = r->sim.mode;
    int rc = ss_sim_next_event(&r->sim, t_stop, &ev);
    if (rc)
      return rc;
    if (ev.from == ev.to) /* a stick grazing does not end the phase */
      continue;
    if (modes && durations) {
      if (r->np >= SS_MAX_PHASES)
        return SS_ELIMIT_EVENTS;
      modes[r->np] = cur;
      durations[r->np] = ev.t - r->t_last;
    }
    r->np++;
    r->t_last = ev.t;
    if (ev.from == SS_MODE_STICK && ev.to == SS_MODE_SLIP &&
        ev.kind == SS_EVENT_TRANSITION) {
      double ze[4];
      ss_x_to_z(r->sim.m, ev.x, ze);
      out[0] = ze[0];
      out[1] = ze[2];
      return SS_OK;
    }
  }
  return SS_ELIMIT_EVENTS;
}

int ss__poincare(const ss_model *m, const double s[2], int turns,
                 size_t max_events, double out[2], ss_mode *modes,
                 double *durations, int *n_phases, ss__poll *poll) {
  ss__returns r;
  int rc = ss__returns_start(&r, m, s);
  r.poll = poll;
  for (int done = 0; done < turns && rc == SS_OK; done++)
    rc = ss__returns_next(&r, &max_events, out, modes, durations);
  if (rc == SS_OK && n_phases)
    *n_phases = r.np;
  return rc;
}

int ss_poincare(const ss_model *m, const double s[2], int turns,
                size_t max_events, double out[2], ss_mode *modes,
                double *durations, int *n_phases) {
  return ss__poincare(m, s, turns, max_events, out, modes, durations, n_phases,
                      NULL);
}

/* Passes through Sigma0 of a sequence: the sticks that end into slip (the
 * last phase ends there by definition). */
static int count_turns(int n, const ss_mode *modes) {
  int turns = 0;
  for (int k = 0; k < n; k++)
    turns += modes[k] == SS_MODE_STICK &&
             (k + 1 == n || modes[k + 1] == SS_MODE_SLIP);
  return turns;
}

/* The analytic Jacobian of the map on Sigma0, in (z1, z1'): the product of
 * the phases' maps with the switching-time corrections of the file's head,
 * carried as the 4 x 2 matrix D of dZ against (x, v).  SS_ESINGULAR when a
 * phase ends tangentially (n.f = 0: no correction exists); jac is then
 * untouched. */
static int map_jacobian(const ss_model *m, int n, const ss_mode *modes,
                        const double *tau, const double z0[4],
                        double jac[2][2]) {
  double D[4][2] = {{1, 0}, {1, 0}, {0, 1}, {0, 0}}, Z[4];
  double chi = m->p.chi;
  memcpy(Z, z0, sizeof Z);
  for (int k = 0; k < n; k++) {
    double A[16], c[4], dA[16], dc[4], f[4], Ze[4], AD[4][2], nv[4] = {0};
    ss_transition(m, modes[k], tau[k], A, c, dA, dc);
    memcpy(Ze, c, sizeof Ze);
    mat4_vec(A, Z, Ze, 1);
    memcpy(f, dc, sizeof f);
    mat4_vec(dA, Z, f, 1);
    if (modes[k] == SS_MODE_STICK) {
      nv[0] = -chi;
      nv[1] = chi;
    } else {
      nv[3] = 1;
    }
    double nf = nv[0] * f[0] + nv[1] * f[1] + nv[2] * f[2] + nv[3] * f[3];
    double fscale = fabs(f[0]) + fabs(f[1]) + fabs(f[2]) + fabs(f[3]);
    if (!(fabs(nf) > 1e-12 * fscale * (fabs(nv[0]) + fabs(nv[1]) + nv[3])))
      return SS_ESINGULAR;
    for (int i = 0; i < 4; i++)
      for (int j = 0; j < 2; j++) {
        double s = 0;
        for (int l = 0; l < 4; l++)
          s += A[4 * i + l] * D[l][j];
        AD[i][j] = s;
      }
    for (int j = 0; j < 2; j++) {
      double nAD = 0;
      for (int l = 0; l < 4; l++)
        nAD += nv[l] * AD[l][j];
      for (int i = 0; i < 4; i++)
        D[i][j] = AD[i][j] - f[i] * nAD / nf;
    }
    memcpy(Z, Ze, sizeof Z);
  }
  jac[0][0] = D[0][0];
  jac[0][1] = D[0][1];
  jac[1][0] = D[2][0];
  jac[1][1] = D[2][1];
  return SS_OK;
}

/* The multipliers of st->jac and the verdicts read from them. */
static void set_multipliers(ss_stab *st) {
  eig2(st->jac, st->eig_re, st->eig_im);
  st->spectral_radius = fmax(hypot(st->eig_re[0], st->eig_im[0]),
                             hypot(st->eig_re[1], st->eig_im[1]));
  st->stable = st->spectral_radius < 1;
  st->unit_margin = 1 - st->spectral_radius;
  st->marginal = fabs(st->unit_margin) <= SS_MARGINAL_TOL;
}

/* Column j of the Jacobian by central differences of the simulated map
 * over @a turns returns, from s0 = (z1, z1').  The step starts at 1e-6
 * (balancing the O(h^2) truncation against rounding of order 1e-16/h) and
 * is divided by 10 while two successive estimates disagree by more than
 * 1e-7 of their size: near a tangential switching the map is smooth only in
 * a small neighbourhood.  When they never agree that well (a long orbit
 * whose rounding grows before its truncation is small), the estimate of the
 * closest successive pair is kept, not the last, which rounding spoils.
 * The choice of h looks only at the differences themselves, never at the
 * analytic Jacobian.  NAN where no estimate could be made. */
static void difference_column(const ss_model *m, int n, int turns,
                              const double s0[2], int j, double col[2]) {
  double est[5][2], best_gap = INFINITY;
  int ne = 0, pick = -1;
  for (double hr = 1e-6; hr >= 1e-10 && ne < 5; hr *= 0.1) {
    double h = hr * (1 + fabs(s0[j])), sp[2], sm[2], op[2], om[2];
    memcpy(sp, s0, sizeof sp);
    memcpy(sm, s0, sizeof sm);
    sp[j] += h;
    sm[j] -= h;
    if (ss_poincare(m, sp, turns, 64 * (size_t)(n + 1), op, NULL, NULL, NULL) ||
        ss_poincare(m, sm, turns, 64 * (size_t)(n + 1), om, NULL, NULL, NULL))
      break;
    est[ne][0] = (op[0] - om[0]) / (sp[j] - sm[j]);
    est[ne][1] = (op[1] - om[1]) / (sp[j] - sm[j]);
    ne++;
    if (ne < 2)
      continue;
    const double *cur = est[ne - 1], *prev = est[ne - 2];
    double size = fmax(1.0, fmax(fabs(cur[0]), fabs(cur[1])));
    double gap = fmax(fabs(cur[0] - prev[0]), fabs(cur[1] - prev[1])) / size;
    if (gap < best_gap) {
      best_gap = gap;
      pick = ne - 1;
    }
    if (gap <= 1e-7)
      break;
  }
  if (pick < 0)
    pick = ne - 1;
  col[0] = pick >= 0 ? est[pick][0] : NAN;
  col[1] = pick >= 0 ? est[pick][1] : NAN;
}

/* The cross-check of the analytic Jacobian: st->jac_fd column by column,
 * and st->jac_diff, the largest difference (NAN if an estimate failed). */
static void difference_check(const ss_model *m, int n, int turns,
                             const double z0[4], ss_stab *st) {
  double s0[2] = {z0[0], z0[2]}, col[2];
  for (int j = 0; j < 2; j++) {
    difference_column(m, n, turns, s0, j, col);
    st->jac_fd[0][j] = col[0];
    st->jac_fd[1][j] = col[1];
  }
  double diff = 0;
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++)
      diff = fmax(diff, fabs(st->jac[i][j] - st->jac_fd[i][j]));
  st->jac_diff = isnan(st->jac_fd[0][0] + st->jac_fd[0][1] + st->jac_fd[1][0] +
                       st->jac_fd[1][1])
                     ? NAN
                     : diff;
}

int ss_stability(const ss_model *m, int n, const ss_mode *modes,
                 const double *tau, const double z0[4],
                 const ss_stab_opts *opts, ss_stab *st) {
  if (!m || !modes || !tau || !z0 || n < 1 || n > SS_MAX_PHASES || !st)
    return SS_EINVAL;
  int turns = opts && opts->turns > 0 ? opts->turns : count_turns(n, modes);
  memset(st, 0, sizeof *st);
  if (map_jacobian(m, n, modes, tau, z0, st->jac) != SS_OK)
    return SS_ESINGULAR; /* st all zero: jac is written only at the end */
  set_multipliers(st);
  st->jac_diff = NAN;
  if (opts && opts->difference_check)
    difference_check(m, n, turns, z0, st);
  return SS_OK;
}
