/* 3-DOF KCS plant dynamics (docs/method.md, paper Eq. 11-12), shared by the KCS and
 * KCSVendorB FMUs so that both integrate the very same equations. SI units throughout.
 * Equations, parameter derivation and sources: models/KCS/readme.md.
 *
 * kcs_parameter_defaults.h is generated at build time from models/KCS/parameter_sets.toml
 * ([default] set) by orchestrator/fmu_build.py: one KCS_DEFAULT_<name> per parameter.
 */
#ifndef KCS_DYNAMICS_H
#define KCS_DYNAMICS_H

#include <math.h>

#include "kcs_parameter_defaults.h"
#include "rk4.h"

#define KCS_GRAVITY 9.81 /* m/s^2 */
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Every plant parameter: X(name, variability). Units in parameter_sets.toml and readme.md. */
#define KCS_PARAMETERS(X)                                                                      \
    X(m11, VariabilityFixed)          /* kg, surge mass incl. added mass */                   \
    X(m22, VariabilityFixed)          /* kg, sway mass incl. added mass */                    \
    X(m33, VariabilityFixed)          /* kg m^2, yaw inertia incl. added inertia */           \
    X(d11, VariabilityFixed)          /* kg/s, linear surge damping */                        \
    X(d22, VariabilityFixed)          /* kg/s, linear sway damping */                         \
    X(d33, VariabilityFixed)          /* kg m^2/s, linear yaw damping */                      \
    X(d23, VariabilityFixed)          /* kg m/s, sway force per yaw rate (with minus sign) */ \
    X(d32, VariabilityFixed)          /* kg m/s, yaw moment per sway speed (minus sign) */    \
    X(tau_u_max, VariabilityTunable)  /* N, surge force bound (input saturation) */           \
    X(tau_r_max, VariabilityTunable)  /* N m, yaw moment bound (input saturation) */          \
    X(lpp, VariabilityTunable)        /* m, length between perpendiculars (loads) */          \
    X(beam, VariabilityTunable)       /* m, beam (wave drift) */                              \
    X(rho_air, VariabilityTunable)    /* kg/m^3 */                                            \
    X(rho_water, VariabilityTunable)  /* kg/m^3 */                                            \
    X(wind_area_frontal, VariabilityTunable) /* m^2 */                                        \
    X(wind_area_lateral, VariabilityTunable) /* m^2 */                                        \
    X(wind_cx, VariabilityTunable)    /* -, wind surge coefficient */                         \
    X(wind_cy, VariabilityTunable)    /* -, wind sway coefficient */                          \
    X(wind_cn, VariabilityTunable)    /* -, wind yaw coefficient */                           \
    X(wave_cx, VariabilityTunable)    /* -, mean wave drift surge coefficient */              \
    X(wave_cy, VariabilityTunable)    /* -, mean wave drift sway coefficient */               \
    X(wave_cn, VariabilityTunable)    /* -, mean wave drift yaw coefficient */                \
    X(h_int, VariabilityTunable)      /* s, internal RK4 step */

typedef struct {
#define KCS_FIELD(name, variability) double name;
    KCS_PARAMETERS(KCS_FIELD)
#undef KCS_FIELD
} KcsParameters;

/* Inputs in SI: tau_u N, tau_r N m, current m/s (earth frame), wind speed m/s,
 * wind direction rad (meteorological: where it comes from, clockwise from north), hs m. */
typedef struct {
    double tau_u, tau_r, current_north, current_east, wind_speed, wind_direction, hs;
} KcsInputs;

enum { KCS_X, KCS_Y, KCS_PSI, KCS_U, KCS_V, KCS_R, KCS_NSTATES };

static inline void kcs_default_parameters(KcsParameters *p) {
#define KCS_DEFAULT(name, variability) p->name = KCS_DEFAULT_##name;
    KCS_PARAMETERS(KCS_DEFAULT)
#undef KCS_DEFAULT
}

/* Wraps an angle to (-pi, pi]. */
static inline double kcs_wrap_angle(double a) {
    double w = fmod(a + M_PI, 2.0 * M_PI);
    if (w <= 0.0) w += 2.0 * M_PI;
    return w - M_PI;
}

static inline double kcs_clamp(double value, double bound) {
    return value > bound ? bound : (value < -bound ? -bound : value);
}

/* Body-frame disturbance w_b = [w_u (N), w_v (N), w_r (N m)] from wind and waves. */
static inline void kcs_disturbance(const KcsParameters *p, const double X[KCS_NSTATES],
                                   const KcsInputs *in, double w[3]) {
    const double psi = X[KCS_PSI], u = X[KCS_U], v = X[KCS_V];
    const double c = cos(psi), s = sin(psi);
    /* ship velocity over ground minus the air velocity, earth frame (m/s) */
    const double rel_n = u * c - v * s + in->current_north + in->wind_speed * cos(in->wind_direction);
    const double rel_e = u * s + v * c + in->current_east + in->wind_speed * sin(in->wind_direction);
    /* ... in the body frame: the apparent wind comes from angle gamma off the bow */
    const double u_rw = c * rel_n + s * rel_e, v_rw = -s * rel_n + c * rel_e;
    const double gamma = atan2(v_rw, u_rw);
    const double q_wind = 0.5 * p->rho_air * (u_rw * u_rw + v_rw * v_rw); /* Pa */
    /* mean wave drift, waves from the wind direction, angle gamma_w off the bow */
    const double gamma_w = in->wind_direction - psi;
    const double q_wave = 0.5 * p->rho_water * KCS_GRAVITY * in->hs * in->hs; /* N/m */

    w[0] = -q_wind * p->wind_cx * p->wind_area_frontal * cos(gamma)
           - q_wave * p->wave_cx * p->beam * cos(gamma_w);
    w[1] = -q_wind * p->wind_cy * p->wind_area_lateral * sin(gamma)
           - q_wave * p->wave_cy * p->lpp * sin(gamma_w);
    w[2] = -q_wind * p->wind_cn * p->wind_area_lateral * p->lpp * sin(2.0 * gamma)
           - q_wave * p->wave_cn * p->lpp * p->lpp * sin(2.0 * gamma_w);
}

/* Right-hand side of the ship model (docs/method.md); tau in `in` is already saturated. */
static inline void kcs_derivatives(const KcsParameters *p, const double X[KCS_NSTATES],
                                   const KcsInputs *in, double dX[KCS_NSTATES]) {
    const double m11 = p->m11, m22 = p->m22, m33 = p->m33;
    const double d11 = p->d11, d22 = p->d22, d33 = p->d33, d23 = p->d23, d32 = p->d32;
    const double psi = X[KCS_PSI], u = X[KCS_U], v = X[KCS_V], r = X[KCS_R];
    double w[3];
    kcs_disturbance(p, X, in, w);
    dX[KCS_X] = u * cos(psi) - v * sin(psi) + in->current_north;
    dX[KCS_Y] = u * sin(psi) + v * cos(psi) + in->current_east;
    dX[KCS_PSI] = r;
    dX[KCS_U] = (m22 * v * r - d11 * u + in->tau_u + w[0]) / m11;
    dX[KCS_V] = (-m11 * u * r - d22 * v - d23 * r + w[1]) / m22;
    dX[KCS_R] = ((m11 - m22) * u * v - d32 * v - d33 * r + in->tau_r + w[2]) / m33;
}

/* kcs_derivatives in the integrator's form (rk4.h). */
static inline void kcs_rk4_derivatives(const void *p, const void *in, const double *X, double *dX) {
    kcs_derivatives((const KcsParameters *)p, X, (const KcsInputs *)in, dX);
}

/* Advances X over `duration` seconds with inputs held constant: RK4 substeps of h_int, the
 * last one shortened to end exactly at the communication point. The inputs tau_u, tau_r are
 * saturated at +-tau_u_max, +-tau_r_max. psi is wrapped to (-pi, pi] afterwards. Returns 0,
 * or -1 when the state became non-finite. */
static inline int kcs_integrate(const KcsParameters *p, double X[KCS_NSTATES],
                                const KcsInputs *in, double duration) {
    KcsInputs sat = *in;
    sat.tau_u = kcs_clamp(in->tau_u, p->tau_u_max);
    sat.tau_r = kcs_clamp(in->tau_r, p->tau_r_max);
    rk4_advance(kcs_rk4_derivatives, p, &sat, X, KCS_NSTATES, p->h_int, duration);
    X[KCS_PSI] = kcs_wrap_angle(X[KCS_PSI]);
    return rk4_finite(X, KCS_NSTATES) ? 0 : -1;
}

/* Speed (m/s) and course (rad, (-pi, pi]) over ground. */
static inline void kcs_over_ground(const double X[KCS_NSTATES], const KcsInputs *in,
                                   double *sog, double *cog) {
    const double n = X[KCS_U] * cos(X[KCS_PSI]) - X[KCS_V] * sin(X[KCS_PSI]) + in->current_north;
    const double e = X[KCS_U] * sin(X[KCS_PSI]) + X[KCS_V] * cos(X[KCS_PSI]) + in->current_east;
    *sog = hypot(n, e);
    *cog = kcs_wrap_angle(atan2(e, n));
}

/* Returns the name of the first parameter that makes the model meaningless, or NULL. */
static inline const char *kcs_invalid_parameter(const KcsParameters *p) {
    if (!(p->m11 > 0.0)) return "m11";
    if (!(p->m22 > 0.0)) return "m22";
    if (!(p->m33 > 0.0)) return "m33";
    if (!(p->tau_u_max >= 0.0)) return "tau_u_max";
    if (!(p->tau_r_max >= 0.0)) return "tau_r_max";
    if (!(p->h_int > 0.0)) return "h_int";
    return NULL;
}

#endif
