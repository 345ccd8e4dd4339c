/*
 * test_modal.c: parameters, modal decomposition, closed-form flows and
 * transition matrices, each against an independent computation.
 */
#include <string.h>

#include <gsl/gsl_errno.h>

#include "refsim.h"
#include "stickslip.h"
#include "test.h"

static const ss_params PAPER = {0.2, 4.0, 0.0724, 0.6178, 1.0};

static const ss_params SETS[] = {
    {0.2, 4.0, 0.0724, 0.6178, 1.0}, {0.5, 1.0, 0.1, 0.3, 0.7},
    {0.05, 20.0, 0.02, 0.5, 2.0},    {0.9, 0.1, 0.3, 0.4, 0.2},
    {1e-3, 1e3, 0.01, 0.05, 1.0},
};

static void test_params(void) {
  ss_diag d;
  ss_params p = PAPER;
  ASSERT_EQ_INT(ss_params_check(&p, NULL), SS_OK);
  /* EVIDENCE: stickslip.h ss_params_check: the validator names the parameter
   * and why */
  struct {
    ss_params p;
    const char *where;
  } bad[] = {
      {{0, 4, 0.07, 0.6, 1}, "chi"},   {{1, 4, 0.07, 0.6, 1}, "chi"},
      {{NAN, 4, 0.07, 0.6, 1}, "chi"}, {{0.2, 0, 0.07, 0.6, 1}, "eta"},
      {{0.2, 4, 0.07, 0.6, 0}, "V"},   {{0.2, 4, 0.6, 0.6, 1}, "us"},
      {{0.2, 4, -0.1, 0.6, 1}, "us"},  {{0.2, 4, 0.07, INFINITY, 1}, "ur"},
      {{0.2, 4, 0.07, 0.6, -1}, "V"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    ss_diag_clear(&d);
    ASSERT_EQ_INT(ss_params_check(&bad[i].p, &d), SS_EDOMAIN);
    ASSERT_TRUE(strcmp(d.where, bad[i].where) == 0);
    ASSERT_TRUE(strlen(d.text) > 10);
  }
  /* each parameter in range, together too extreme for doubles */
  {
    ss_model m;
    ss_params big = {0.5, 1e300, 0.1, 0.2, 1},
              tiny = {1e-300, 1e-300, 0.1, 0.2, 1};
    ss_diag_clear(&d);
    ASSERT_EQ_INT(ss_model_init(&m, &big, &d), SS_EDOMAIN);
    ASSERT_TRUE(strstr(d.text, "too extreme") != NULL);
    ss_diag_clear(&d);
    ASSERT_EQ_INT(ss_model_init(&m, &tiny, &d), SS_EDOMAIN);
  }
  /* physical units: k1 + k2 = 10, m1 = 2.5 -> omega = 2 */
  ss_physical ph = {2.5, 0.625, 8, 2, 0.724, 6.178, 2.0};
  double om;
  ASSERT_EQ_INT(ss_params_from_physical(&ph, &p, &om, NULL), SS_OK);
  ASSERT_NEAR(om, 2.0, 1e-15);
  ASSERT_NEAR(p.chi, 0.2, 1e-15);
  ASSERT_NEAR(p.eta, 4.0, 1e-15);
  ASSERT_NEAR(p.us, 0.0724, 1e-15);
  ASSERT_NEAR(p.ur, 0.6178, 1e-15);
  ASSERT_NEAR(p.V, 1.0, 1e-15);
  ph.Fs = 7;
  ss_diag_clear(&d);
  ASSERT_EQ_INT(ss_params_from_physical(&ph, &p, &om, &d), SS_EDOMAIN);
  ASSERT_TRUE(strcmp(d.where, "Fs") == 0);
  double x[4] = {1, 2, 3, 4}, xp[4], t, xb[4];
  ss_to_physical(2.0, 5.0, x, &t, xp);
  ASSERT_NEAR(t, 2.5, 0);
  ASSERT_NEAR(xp[2], 6, 0);
  ss_from_physical(2.0, t, xp, &t, xb);
  ASSERT_NEAR(t, 5, 0);
  ASSERT_NEAR(xb[3], 4, 0);
}

static void test_modal_data(void) {
  for (size_t s = 0; s < sizeof SETS / sizeof SETS[0]; s++) {
    ss_model m;
    ASSERT_EQ_INT(ss_model_init(&m, &SETS[s], NULL), SS_OK);
    double chi = m.p.chi, eta = m.p.eta;
    double K[2][2] = {{1, -chi}, {-chi * eta, chi * eta}};
    ASSERT_TRUE(m.lam[0] > 0 && m.lam[1] > m.lam[0]);
    for (int k = 0; k < 2; k++)
      for (int i = 0; i < 2; i++) {
        double Kp = K[i][0] * m.phi[0][k] + K[i][1] * m.phi[1][k];
        ASSERT_NEAR(Kp, m.lam[k] * m.phi[i][k], 1e-14 * (1 + m.lam[1]));
      }
    /* K d0 = (0, eta us) */
    ASSERT_NEAR(K[0][0] * m.d0[0] + K[0][1] * m.d0[1], 0, 1e-14 * m.d0[1]);
    ASSERT_NEAR(K[1][0] * m.d0[0] + K[1][1] * m.d0[1], eta * m.p.us,
                1e-13 * eta * m.d0[1]);
  }
}

static const ref_opts TIGHT = {NULL, 1e-14, 1e-14, 0, 0};

/* EVIDENCE: docs/checked/index.md (closed forms):
 * "Checked against GSL rk8pd at tolerance 1e-14 on five parameter sets and
 * three states in each mode" (README: largest difference 1.2e-13 relative to
 * 1 + |d0|; asserted here to 1e-10). */
static void test_flow_vs_odeiv2(void) {
  ref_opts o = TIGHT;
  o.type = gsl_odeiv2_step_rk8pd;
  double maxerr = 0;
  for (size_t s = 0; s < sizeof SETS / sizeof SETS[0]; s++) {
    ss_model m;
    ss_model_init(&m, &SETS[s], NULL);
    ref_params rp = {m.p.chi, m.p.eta, m.p.us, m.p.ur, m.p.V};
    const double states[3][4] = {
        {1.1844, 3.9116, -0.8075, 0.3}, {-0.5, 0.2, 1.0, -1.5}, {0, 0, 0, 0}};
    for (int mode = 0; mode < 3; mode++)
      for (int k = 0; k < 3; k++)
        for (double t = 0.37; t < 12; t *= 2.3) {
          double x0[4], xc[4], xr[4];
          memcpy(x0, states[k], sizeof x0);
          if (mode == SS_MODE_STICK)
            x0[3] = m.p.V;
          ss_flow(&m, (ss_mode)mode, t, x0, xc);
          memcpy(xr, x0, sizeof xr);
          ASSERT_EQ_INT(ref_flow(&rp, mode, t, xr, &o), GSL_SUCCESS);
          double scale = 1 + fabs(m.d0[1]);
          for (int i = 0; i < 4; i++) {
            double e = fabs(xc[i] - xr[i]) / scale;
            if (e > maxerr)
              maxerr = e;
            ASSERT_NEAR(xc[i], xr[i], 1e-10 * scale);
          }
        }
  }
  printf("flow vs rk8pd: max error %.3g (relative to 1 + |d0|)\n", maxerr);
}

/* The transition matrices reproduce the flow, and their derivatives match
 * central differences. */
static void test_transition(void) {
  for (size_t s = 0; s < sizeof SETS / sizeof SETS[0]; s++) {
    ss_model m;
    ss_model_init(&m, &SETS[s], NULL);
    for (int mode = 0; mode < 3; mode++) {
      double x0[4] = {0.3, -0.2, 0.4, mode == SS_MODE_STICK ? m.p.V : -0.7};
      double z0[4], A[16], c[4], dA[16], dc[4], xf[4], zf[4];
      double t = 2.1;
      ss_x_to_z(&m, x0, z0);
      ss_transition(&m, (ss_mode)mode, t, A, c, dA, dc);
      ss_flow(&m, (ss_mode)mode, t, x0, xf);
      ss_x_to_z(&m, xf, zf);
      for (int i = 0; i < 4; i++) {
        double zi = c[i];
        for (int j = 0; j < 4; j++)
          zi += A[4 * i + j] * z0[j];
        ASSERT_NEAR(zi, zf[i], 1e-12 * (1 + fabs(m.d0[1])));
      }
      double h = 1e-5, Ap[16], Am[16], cp[4], cm[4];
      ss_transition(&m, (ss_mode)mode, t + h, Ap, cp, NULL, NULL);
      ss_transition(&m, (ss_mode)mode, t - h, Am, cm, NULL, NULL);
      for (int i = 0; i < 16; i++)
        ASSERT_NEAR(dA[i], (Ap[i] - Am[i]) / (2 * h), 1e-8);
      for (int i = 0; i < 4; i++)
        ASSERT_NEAR(dc[i], (cp[i] - cm[i]) / (2 * h),
                    1e-8 * (1 + fabs(m.d0[1])));
    }
  }
}

/* EVIDENCE: stickslip.h ss_mode_of_state and README "The model" (thresholds):
 * the rule */
static void test_mode_rule(void) {
  ss_model m;
  ss_model_init(&m, &PAPER, NULL);
  double chi = m.p.chi, ur = m.p.ur, V = m.p.V;
  double x[4] = {0, 0, 0, 0.5};
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_SLIP);
  x[3] = 1.5;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_OVERSHOOT);
  x[3] = V;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_STICK);
  x[1] = 1.01 * ur / chi;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_SLIP);
  x[1] = -1.01 * ur / chi;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_OVERSHOOT);
  /* exactly at +ur: x1' < V means the force grows (chi (V - x1') > 0):
   * slip; x1' > V: the force falls back: stick */
  x[0] = 0;
  x[1] = ur / chi;
  x[2] = -0.8;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_SLIP);
  x[2] = 1.5;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_STICK);
  /* at -ur: leaving downward means x1' > V */
  x[1] = -ur / chi;
  x[2] = 1.5;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_OVERSHOOT);
  x[2] = 0.5;
  ASSERT_EQ_INT(ss_mode_of_state(&m, x), SS_MODE_STICK);
}

/* EVIDENCE: stickslip.h SS_VERSION, ss_version(): the version is written
 * once, as three numbers, and the library reports the one it was built
 * with; SS_STATUS_MAP: SS_ABOVE is information, with a name and message. */
static void test_version_and_status(void) {
  char want[32];
  snprintf(want, sizeof want, "%d.%d.%d", SS_VERSION_MAJOR, SS_VERSION_MINOR,
           SS_VERSION_PATCH);
  ASSERT_TRUE(strcmp(SS_VERSION, want) == 0);
  ASSERT_TRUE(strcmp(ss_version(), SS_VERSION) == 0);
  ASSERT_EQ_INT(SS_VERSION_HEX, SS_VERSION_MAJOR * 65536 +
                                    SS_VERSION_MINOR * 256 + SS_VERSION_PATCH);
  ASSERT_TRUE(SS_VERSION_HEX >= 0x000200); /* the API of this header */
  ASSERT_EQ_INT(SS_ABOVE, 5);
  ASSERT_TRUE(strcmp(ss_status_name(SS_ABOVE), "ABOVE") == 0);
  ASSERT_TRUE(strcmp(ss_strerror(SS_ABOVE), "unknown status") != 0);
  ASSERT_TRUE(strcmp(ss_status_name(SS_EINVAL), "EINVAL") == 0);
  ASSERT_TRUE(strcmp(ss_status_name(99), "UNKNOWN") == 0);
}

int main(void) {
  gsl_set_error_handler_off();
  test_version_and_status();
  test_params();
  test_modal_data();
  test_flow_vs_odeiv2();
  test_transition();
  test_mode_rule();
  TEST_DONE();
}
