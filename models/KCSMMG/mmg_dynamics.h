/* KCS in MMG form (Yasukawa & Yoshimura 2015 standard structure): hull forces from
 * non-dimensional derivatives, propeller thrust from K_T(J) with a drift-dependent wake,
 * rudder normal force with flow straightening and hull-rudder interaction, a rate-limited
 * steering gear and engine. Wind and wave loads are those of the 3-DOF KCS plant
 * (kcs_disturbance in models/common/kcs_dynamics.h). SI units; equations and sources in
 * models/KCSMMG/readme.md.
 *
 * model_parameter_defaults.h is generated at build time from models/KCSMMG/parameter_sets.toml
 * ([default] set) by orchestrator/fmu_build.py: one MODEL_DEFAULT_<name> per parameter.
 */
#ifndef MMG_DYNAMICS_H
#define MMG_DYNAMICS_H

#include <math.h>

#include "kcs_dynamics.h"
#include "model_parameter_defaults.h"

/* Every plant parameter: X(name, variability). Units in parameter_sets.toml and readme.md. */
#define MMG_PARAMETERS(X)                                                                        \
    X(lpp, VariabilityFixed) X(beam, VariabilityFixed) X(draught, VariabilityFixed)             \
    X(displacement, VariabilityFixed) X(rho_water, VariabilityFixed) X(rho_air, VariabilityTunable) \
    X(x_g, VariabilityFixed) X(k_zz, VariabilityFixed) X(m_x, VariabilityFixed)                 \
    X(m_y, VariabilityFixed) X(j_z, VariabilityFixed)                                          \
    X(r0_prime, VariabilityFixed) X(x_vv, VariabilityFixed) X(x_vr, VariabilityFixed)                 \
    X(x_rr, VariabilityFixed) X(x_vvvv, VariabilityFixed)                                      \
    X(y_v, VariabilityFixed) X(y_r, VariabilityFixed) X(y_vvv, VariabilityFixed)                \
    X(y_vvr, VariabilityFixed) X(y_vrr, VariabilityFixed) X(y_rrr, VariabilityFixed)            \
    X(n_v, VariabilityFixed) X(n_r, VariabilityFixed) X(n_vvv, VariabilityFixed)                \
    X(n_vvr, VariabilityFixed) X(n_vrr, VariabilityFixed) X(n_rrr, VariabilityFixed)            \
    X(prop_diameter, VariabilityFixed) X(x_p, VariabilityFixed) X(w_p0, VariabilityFixed)       \
    X(t_p, VariabilityFixed) X(wake_c1, VariabilityFixed) X(wake_c2_plus, VariabilityFixed)     \
    X(wake_c2_minus, VariabilityFixed)                                                         \
    X(k_t0, VariabilityFixed) X(k_t1, VariabilityFixed) X(k_t2, VariabilityFixed)               \
    X(k_q0, VariabilityFixed) X(k_q1, VariabilityFixed) X(k_q2, VariabilityFixed)               \
    X(rudder_area, VariabilityFixed) X(f_alpha, VariabilityFixed) X(rudder_eta, VariabilityFixed) \
    X(epsilon, VariabilityFixed) X(kappa, VariabilityFixed) X(t_r, VariabilityFixed)            \
    X(a_h, VariabilityFixed) X(x_h, VariabilityFixed) X(x_r, VariabilityFixed)                  \
    X(gamma_r_plus, VariabilityFixed) X(gamma_r_minus, VariabilityFixed) X(l_r, VariabilityFixed) \
    X(rudder_max, VariabilityTunable) X(rudder_rate_max, VariabilityTunable)                   \
    X(rudder_time_constant, VariabilityTunable) X(propeller_rps_max, VariabilityTunable)       \
    X(propeller_rate_max, VariabilityTunable) X(propeller_time_constant, VariabilityTunable)   \
    X(wind_area_frontal, VariabilityTunable) X(wind_area_lateral, VariabilityTunable)          \
    X(wind_cx, VariabilityTunable) X(wind_cy, VariabilityTunable) X(wind_cn, VariabilityTunable) \
    X(wave_cx, VariabilityTunable) X(wave_cy, VariabilityTunable) X(wave_cn, VariabilityTunable) \
    X(h_int, VariabilityTunable)

typedef struct {
#define MMG_FIELD(name, variability) double name;
    MMG_PARAMETERS(MMG_FIELD)
#undef MMG_FIELD
} MmgParameters;

/* Inputs in SI: rudder angle command rad (positive turns the ship to starboard), propeller
 * revolutions command 1/s, then the met-ocean inputs of the 3-DOF plant. */
typedef struct {
    double rudder_angle_cmd, propeller_rps_cmd;
    double current_north, current_east, wind_speed, wind_direction, hs;
} MmgInputs;

enum { MMG_X, MMG_Y, MMG_PSI, MMG_U, MMG_V, MMG_R, MMG_DELTA, MMG_N, MMG_NSTATES };

/* What the plant reports besides its state. */
typedef struct {
    double thrust;          /* N */
    double torque;          /* N m */
    double delivered_power; /* W, 2 pi n Q */
    double rudder_force;    /* N, normal force F_N */
} MmgReport;

static inline void mmg_default_parameters(MmgParameters *p) {
#define MMG_DEFAULT(name, variability) p->name = MODEL_DEFAULT_##name;
    MMG_PARAMETERS(MMG_DEFAULT)
#undef MMG_DEFAULT
}

static inline double mmg_clip(double value, double low, double high) {
    return value > high ? high : (value < low ? low : value);
}

/* Hull + propeller + rudder forces F = [X, Y, N about midship] (N, N, N m). */
static inline void mmg_forces(const MmgParameters *p, double u, double v, double r, double delta,
                              double n, double F[3], MmgReport *report) {
    const double rho = p->rho_water, L = p->lpp, d = p->draught, D = p->prop_diameter;
    const double U = hypot(u, v);
    const double vp = U > 1e-9 ? v / U : 0.0, rp = U > 1e-9 ? r * L / U : 0.0;
    const double q = 0.5 * rho * L * d * U * U;
    const double XH = q * (-p->r0_prime + p->x_vv * vp * vp + p->x_vr * vp * rp + p->x_rr * rp * rp
                           + p->x_vvvv * vp * vp * vp * vp);
    const double YH = q * (p->y_v * vp + p->y_r * rp + p->y_vvv * vp * vp * vp + p->y_vvr * vp * vp * rp
                           + p->y_vrr * vp * rp * rp + p->y_rrr * rp * rp * rp);
    const double NH = q * L * (p->n_v * vp + p->n_r * rp + p->n_vvv * vp * vp * vp
                               + p->n_vvr * vp * vp * rp + p->n_vrr * vp * rp * rp + p->n_rrr * rp * rp * rp);
    /* propeller: effective wake changes with the drift angle at the propeller */
    const double beta = U > 1e-9 ? atan2(-v, u) : 0.0;
    const double beta_p = beta - p->x_p * rp;
    const double c2 = beta_p > 0.0 ? p->wake_c2_plus : p->wake_c2_minus;
    const double one_minus_w = (1.0 - p->w_p0) * (1.0 + (1.0 - exp(-p->wake_c1 * fabs(beta_p))) * (c2 - 1.0));
    const double ua = u * one_minus_w, nd = n * D;
    /* rho n^2 D^4 K_T(J) with J = ua / (n D), written without dividing by n */
    const double thrust = rho * D * D * (p->k_t0 * nd * nd + p->k_t1 * nd * ua + p->k_t2 * ua * ua);
    const double torque = rho * D * D * D * (p->k_q0 * nd * nd + p->k_q1 * nd * ua + p->k_q2 * ua * ua);
    /* rudder inflow: propeller slipstream (momentum theory) and flow straightening */
    const double loading = 8.0 * thrust / (M_PI * rho * D * D);
    const double slip = sqrt(ua * ua + (loading > 0.0 ? loading : 0.0));
    const double eta = p->rudder_eta, inner = ua + p->kappa * (slip - ua);
    const double uR = p->epsilon * sqrt(eta * inner * inner + (1.0 - eta) * ua * ua);
    const double beta_r = beta - p->l_r * rp;
    const double vR = U * (beta_r >= 0.0 ? p->gamma_r_plus : p->gamma_r_minus) * beta_r;
    const double alpha = delta - atan2(vR, uR);
    const double FN = 0.5 * rho * p->rudder_area * (uR * uR + vR * vR) * p->f_alpha * sin(alpha);
    F[0] = XH + (1.0 - p->t_p) * thrust - (1.0 - p->t_r) * FN * sin(delta);
    F[1] = YH - (1.0 + p->a_h) * FN * cos(delta);
    F[2] = NH - (p->x_r * L + p->a_h * p->x_h * L) * FN * cos(delta);
    if (report) {
        report->thrust = thrust;
        report->torque = torque;
        report->delivered_power = 2.0 * M_PI * n * torque;
        report->rudder_force = FN;
    }
}

/* The 3-DOF plant's wind and wave loads on this hull (same formulas, this ship's areas). */
static inline void mmg_loads(const MmgParameters *p, const double X[MMG_NSTATES], const MmgInputs *in,
                             double w[3]) {
    KcsParameters k = {0};
    KcsInputs kin = {0.0, 0.0, in->current_north, in->current_east, in->wind_speed, in->wind_direction, in->hs};
    double kx[KCS_NSTATES] = {X[MMG_X], X[MMG_Y], X[MMG_PSI], X[MMG_U], X[MMG_V], X[MMG_R]};
    k.lpp = p->lpp;
    k.beam = p->beam;
    k.rho_air = p->rho_air;
    k.rho_water = p->rho_water;
    k.wind_area_frontal = p->wind_area_frontal;
    k.wind_area_lateral = p->wind_area_lateral;
    k.wind_cx = p->wind_cx;
    k.wind_cy = p->wind_cy;
    k.wind_cn = p->wind_cn;
    k.wave_cx = p->wave_cx;
    k.wave_cy = p->wave_cy;
    k.wave_cn = p->wave_cn;
    kcs_disturbance(&k, kx, &kin, w);
}

/* MMG equations of motion about midship with the centre of gravity at x_g, plus the
 * rate-limited steering gear and engine. */
static inline void mmg_derivatives(const MmgParameters *p, const double X[MMG_NSTATES],
                                   const MmgInputs *in, double dX[MMG_NSTATES]) {
    const double m = p->rho_water * p->displacement, xg = p->x_g;
    const double izz = m * p->k_zz * p->k_zz + xg * xg * m + p->j_z;
    const double psi = X[MMG_PSI], u = X[MMG_U], v = X[MMG_V], r = X[MMG_R];
    double F[3], w[3];
    mmg_forces(p, u, v, r, X[MMG_DELTA], X[MMG_N], F, NULL);
    mmg_loads(p, X, in, w);
    {
        const double Xf = F[0] + w[0], Yf = F[1] + w[1], Nf = F[2] + w[2];
        /* [m + m_y, x_g m; x_g m, I_zz] [vdot; rdot] = [Y - (m + m_x) u r; N - x_g m u r] */
        const double a11 = m + p->m_y, a12 = xg * m, a22 = izz;
        const double b1 = Yf - (m + p->m_x) * u * r, b2 = Nf - xg * m * u * r;
        const double det = a11 * a22 - a12 * a12;
        const double delta_cmd = mmg_clip(in->rudder_angle_cmd, -p->rudder_max, p->rudder_max);
        const double n_cmd = mmg_clip(in->propeller_rps_cmd, 0.0, p->propeller_rps_max);
        dX[MMG_X] = u * cos(psi) - v * sin(psi) + in->current_north;
        dX[MMG_Y] = u * sin(psi) + v * cos(psi) + in->current_east;
        dX[MMG_PSI] = r;
        dX[MMG_U] = (Xf + (m + p->m_y) * v * r + xg * m * r * r) / (m + p->m_x);
        dX[MMG_V] = (a22 * b1 - a12 * b2) / det;
        dX[MMG_R] = (a11 * b2 - a12 * b1) / det;
        dX[MMG_DELTA] = mmg_clip((delta_cmd - X[MMG_DELTA]) / p->rudder_time_constant,
                                 -p->rudder_rate_max, p->rudder_rate_max);
        dX[MMG_N] = mmg_clip((n_cmd - X[MMG_N]) / p->propeller_time_constant,
                             -p->propeller_rate_max, p->propeller_rate_max);
    }
}

/* mmg_derivatives in the integrator's form (rk4.h). */
static inline void mmg_rk4_derivatives(const void *p, const void *in, const double *X, double *dX) {
    mmg_derivatives((const MmgParameters *)p, X, (const MmgInputs *)in, dX);
}

/* Advances X over `duration` seconds with inputs held constant (RK4 substeps of h_int, the
 * last one ending on the communication point). Returns 0, or -1 on a non-finite state. */
static inline int mmg_integrate(const MmgParameters *p, double X[MMG_NSTATES], const MmgInputs *in,
                                double duration) {
    rk4_advance(mmg_rk4_derivatives, p, in, X, MMG_NSTATES, p->h_int, duration);
    X[MMG_PSI] = kcs_wrap_angle(X[MMG_PSI]);
    return rk4_finite(X, MMG_NSTATES) ? 0 : -1;
}

/* Returns the name of the first parameter that makes the model meaningless, or NULL. */
static inline const char *mmg_invalid_parameter(const MmgParameters *p) {
    if (!(p->lpp > 0.0)) return "lpp";
    if (!(p->draught > 0.0)) return "draught";
    if (!(p->displacement > 0.0)) return "displacement";
    if (!(p->rho_water > 0.0)) return "rho_water";
    if (!(p->prop_diameter > 0.0)) return "prop_diameter";
    if (!(p->rudder_max > 0.0)) return "rudder_max";
    if (!(p->rudder_rate_max > 0.0)) return "rudder_rate_max";
    if (!(p->rudder_time_constant > 0.0)) return "rudder_time_constant";
    if (!(p->propeller_rps_max > 0.0)) return "propeller_rps_max";
    if (!(p->propeller_rate_max > 0.0)) return "propeller_rate_max";
    if (!(p->propeller_time_constant > 0.0)) return "propeller_time_constant";
    if (!(p->h_int > 0.0)) return "h_int";
    return NULL;
}

#endif
