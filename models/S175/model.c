/* S175 plant FMU: the ITTC S-175 container ship (Lpp 175 m, B 25.4 m, T 8.5 m, Cb 0.572) in
 * surge, sway and yaw, written as a vendor would: its own variable names and units, position
 * as latitude/longitude on the WGS84 ellipsoid, a quadratic hull resistance. Steered by a
 * surge force and a yaw moment (actuator_mode = 0, the default) or by a rudder order and a
 * shaft speed order (actuator_mode = 1: steering gear, shaft, propeller K_T(J) and a rudder
 * that stalls, after Son and Nomoto 1981). Coefficients: models/S175/derive.py and readme.md.
 * Internally SI. */
#include <math.h>
#include <string.h>

#include "fmu_model.h"
#include "plant_step.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define KNOT (1852.0 / 3600.0)
#define DEG (M_PI / 180.0)
#define WGS84_A 6378137.0
#define WGS84_E2 6.69437999014e-3

/* hull and loads, from derive.py (Clarke 1983 at 18 kn, ITTC-57 resistance, Fujii rudder) */
static const double M11 = 2.348099e7, M22 = 4.588937e7, M33 = 8.260819e10; /* kg, kg, kg m^2 */
static const double X_UU = 5.199225e3;                 /* N/(m/s)^2, R = X_UU u|u| */
static const double D22 = 1.813675e6, D33 = 9.410471e9; /* kg/s, kg m^2/s */
static const double D23 = -9.143294e7, D32 = -9.127267e7; /* kg m/s */
static const double RHO_AIR = 1.225, RHO_WATER = 1025.0, GRAVITY = 9.81;
static const double LPP = 175.0, BEAM = 25.4;
static const double AREA_FRONTAL = 640.0, AREA_LATERAL = 3000.0; /* m^2 */
static const double WIND_CX = 0.7, WIND_CY = 0.85, WIND_CN = 0.1;
static const double WAVE_CX = 0.1, WAVE_CY = 0.03, WAVE_CN = 0.005;
/* propeller, rudder and shaft (Son and Nomoto 1981; readme.md) */
static const double D_P = 6.533, KT0 = 0.527, KT1 = -0.455;          /* m; K_T(J) = KT0 + KT1 J */
static const double W_P = 0.184, T_P = 0.175, TAU_P = 1.09, XP_PROP = -0.526; /* wake in drift: x'_P */
static const double A_R = 33.0376, F_ALPHA = 2.742761;               /* m^2; 6.13 a / (a + 2.25), a = 1.8219 */
static const double EPSILON = 0.921, KAPPA = 0.631, T_R = 0.29;      /* 1 - t_R = c_RX = 0.71 */
static const double A_H = 0.237, X_H = -0.48, X_R = -0.5;
static const double GAMMA_R = 0.088, C_RR = -0.156, C_RRRR = -0.275, C_RRRV = 1.96; /* rudder inflow angle */
static const double SHAFT_TIME = 5.65, SHAFT_TIME_SLOW = 18.83;     /* s 1/s above 0.3 1/s; s below */
/* ours (readme.md): steering gear, stall, largest revolutions */
static const double RUDDER_MAX = 35.0 * DEG, RUDDER_RATE = 2.32 * DEG; /* rad, rad/s */
static const double STALL = 30.0 * DEG, STALL_DROP = 5.0 * DEG, POST_STALL = 0.6;
static const double RPM_MAX = 107.0;                                  /* 1/min, ahead only */

#define IN(name) {vr_##name, #name, TypeReal, CausalityInput, VariabilityContinuous}
#define OUT(name) {vr_##name, #name, TypeReal, CausalityOutput, VariabilityContinuous}
#define FIXED(name) {vr_##name, #name, TypeReal, CausalityParameter, VariabilityFixed}
#define TUNABLE(name) {vr_##name, #name, TypeReal, CausalityParameter, VariabilityTunable}

const ModelVariable model_variables[N_VARIABLES] = {
    IN(propeller_thrust), IN(rudder_moment), IN(current_set), IN(current_drift),
    IN(wind_speed_true), IN(wind_from), IN(wave_height),
    OUT(lat), OUT(lon), OUT(north_km), OUT(east_km), OUT(heading), OUT(stw), OUT(sway_speed),
    OUT(rot), OUT(sog), OUT(cog),
    FIXED(start_lat), FIXED(start_lon), FIXED(start_heading), FIXED(start_stw),
    TUNABLE(max_thrust), TUNABLE(max_rudder_moment), TUNABLE(internal_step),
    IN(rudder_order), IN(shaft_speed_order), OUT(rudder_position), OUT(shaft_speed), OUT(shaft_thrust),
    FIXED(actuator_mode), FIXED(start_shaft_speed),
};

static double *field(ModelData *d, fmi2ValueReference vr) {
    switch (vr) {
    case vr_propeller_thrust: return &d->thrust_kN;
    case vr_rudder_moment: return &d->moment_kNm;
    case vr_current_set: return &d->set_deg;
    case vr_current_drift: return &d->drift_kn;
    case vr_wind_speed_true: return &d->wind_kn;
    case vr_wind_from: return &d->wind_from_deg;
    case vr_wave_height: return &d->hs_m;
    case vr_start_lat: return &d->start_lat_deg;
    case vr_start_lon: return &d->start_lon_deg;
    case vr_start_heading: return &d->start_heading_deg;
    case vr_start_stw: return &d->start_stw_kn;
    case vr_max_thrust: return &d->max_thrust_kN;
    case vr_max_rudder_moment: return &d->max_moment_kNm;
    case vr_internal_step: return &d->h_int_s;
    case vr_rudder_order: return &d->rudder_order_deg;
    case vr_shaft_speed_order: return &d->shaft_order_rpm;
    case vr_actuator_mode: return &d->actuator_mode;
    case vr_start_shaft_speed: return &d->start_shaft_rpm;
    default: return NULL;
    }
}

static int actuator_mode(const ModelData *d) { return d->actuator_mode > 0.5; }

/* Rudder normal-force coefficient at the effective angle alpha (rad): the lift slope up to the
 * stall angle, then falling linearly over STALL_DROP to POST_STALL of its peak. */
static double rudder_normal_coefficient(double alpha) {
    const double a = fabs(alpha);
    if (a <= STALL) return F_ALPHA * sin(alpha);
    return copysign(F_ALPHA * sin(STALL) * (1.0 - (1.0 - POST_STALL) * fmin((a - STALL) / STALL_DROP, 1.0)), alpha);
}

/* Propeller and rudder at the state X: forces F = [X, Y, N] about midship (N, N, N m) and
 * the propeller thrust (N). Son and Nomoto's form: the wake falls with the drift at the
 * propeller, the slipstream speeds the rudder inflow up, the hull straightens its angle. */
static void actuator_loads(const double X[S_NSTATES], double F[3], double *thrust) {
    const double u = X[S_U], v = X[S_V], r = X[S_R], delta = X[S_DELTA], nd = X[S_N] * D_P;
    const double U = hypot(u, v), vp = U > 1e-6 ? v / U : 0.0, rp = U > 1e-6 ? r * LPP / U : 0.0;
    const double drift_p = vp + XP_PROP * rp;
    const double uP = u * ((1.0 - W_P) + TAU_P * drift_p * drift_p);            /* propeller advance speed */
    const double T = RHO_WATER * D_P * D_P * (KT0 * nd * nd + KT1 * nd * uP);      /* rho n^2 D^4 K_T(J) */
    const double uR = EPSILON * sqrt(fmax(uP * uP + 8.0 * KAPPA * T / (M_PI * RHO_WATER * D_P * D_P), 0.0));
    const double vR = U * (GAMMA_R * vp + C_RR * rp + C_RRRR * rp * rp * rp + C_RRRV * rp * rp * vp);
    const double FN = 0.5 * RHO_WATER * A_R * (uR * uR + vR * vR) * rudder_normal_coefficient(delta + atan2(vR, uR));
    F[0] = (1.0 - T_P) * T - (1.0 - T_R) * FN * sin(delta);
    F[1] = -(1.0 + A_H) * FN * cos(delta);
    F[2] = -(X_R + A_H * X_H) * LPP * FN * cos(delta);
    *thrust = T;
}

/* Earth-frame velocity over ground (m/s): through the water plus the current. */
static void over_ground(const ModelData *d, const double X[S_NSTATES], double *vn, double *ve) {
    const double c = cos(X[S_PSI]), s = sin(X[S_PSI]);
    const double set = d->set_deg * DEG, drift = d->drift_kn * KNOT;
    *vn = X[S_U] * c - X[S_V] * s + drift * cos(set);
    *ve = X[S_U] * s + X[S_V] * c + drift * sin(set);
}

static void derivatives(const ModelData *d, const double X[S_NSTATES], double dX[S_NSTATES]) {
    const double psi = X[S_PSI], u = X[S_U], v = X[S_V], r = X[S_R];
    double tau_u = plant_clip(d->thrust_kN, -d->max_thrust_kN, d->max_thrust_kN) * 1e3;
    double tau_r = plant_clip(d->moment_kNm, -d->max_moment_kNm, d->max_moment_kNm) * 1e3;
    double rudder_sway = 0.0, steering[3], thrust;
    const double sin_lat = sin(X[S_LAT]), w = 1.0 - WGS84_E2 * sin_lat * sin_lat;
    const double radius_m = WGS84_A * (1.0 - WGS84_E2) / (w * sqrt(w)); /* meridian */
    const double radius_n = WGS84_A / sqrt(w);                         /* prime vertical */
    double vn, ve, wind[3];
    if (actuator_mode(d)) {
        actuator_loads(X, steering, &thrust);
        tau_u = steering[0];
        rudder_sway = steering[1];
        tau_r = steering[2];
    }
    over_ground(d, X, &vn, &ve);
    {   /* apparent wind and mean wave drift, as in the KCS plant's disturbance model */
        const double c = cos(psi), s = sin(psi), from = d->wind_from_deg * DEG, ws = d->wind_kn * KNOT;
        const double rel_n = vn + ws * cos(from), rel_e = ve + ws * sin(from);
        const double u_rw = c * rel_n + s * rel_e, v_rw = -s * rel_n + c * rel_e;
        const double gamma = atan2(v_rw, u_rw), q = 0.5 * RHO_AIR * (u_rw * u_rw + v_rw * v_rw);
        const double gamma_w = from - psi, qw = 0.5 * RHO_WATER * GRAVITY * d->hs_m * d->hs_m;
        wind[0] = -q * WIND_CX * AREA_FRONTAL * cos(gamma) - qw * WAVE_CX * BEAM * cos(gamma_w);
        wind[1] = -q * WIND_CY * AREA_LATERAL * sin(gamma) - qw * WAVE_CY * LPP * sin(gamma_w);
        wind[2] = -q * WIND_CN * AREA_LATERAL * LPP * sin(2.0 * gamma) - qw * WAVE_CN * LPP * LPP * sin(2.0 * gamma_w);
    }
    dX[S_LAT] = vn / radius_m;
    dX[S_LON] = ve / (radius_n * cos(X[S_LAT]));
    dX[S_NORTH] = vn;
    dX[S_EAST] = ve;
    dX[S_PSI] = r;
    dX[S_U] = (M22 * v * r - X_UU * u * fabs(u) + tau_u + wind[0]) / M11;
    dX[S_V] = (-M11 * u * r - D22 * v - D23 * r + wind[1] + rudder_sway) / M22;
    dX[S_R] = ((M11 - M22) * u * v - D32 * v - D33 * r + tau_r + wind[2]) / M33;
    if (actuator_mode(d)) {   /* steering gear at its rate; shaft lagging its order by 5.65 s / n */
        const double n = X[S_N], n_order = plant_clip(d->shaft_order_rpm, 0.0, RPM_MAX) / 60.0;
        dX[S_DELTA] = plant_clip(plant_clip(d->rudder_order_deg * DEG, -RUDDER_MAX, RUDDER_MAX) - X[S_DELTA],
                                 -RUDDER_RATE, RUDDER_RATE);
        dX[S_N] = (n_order - n) / (n > 0.3 ? SHAFT_TIME / n : SHAFT_TIME_SLOW);
    } else {
        dX[S_DELTA] = dX[S_N] = 0.0;
    }
}

void model_set_start_values(ModelInstance *comp) {
    ModelData *d = &comp->data;
    memset(d, 0, sizeof *d);
    d->max_thrust_kN = 800.0;     /* resistance at 23 kn + 10 % */
    d->max_moment_kNm = 1.65e5;   /* rudder L T / 50 at 35 deg, 18 kn inflow, lever L/2 */
    d->h_int_s = 0.5;
}

static void initial_state(ModelData *d, double X[S_NSTATES]) {
    memset(X, 0, S_NSTATES * sizeof X[0]);
    X[S_LAT] = d->start_lat_deg * DEG;
    X[S_LON] = d->start_lon_deg * DEG;
    X[S_PSI] = d->start_heading_deg * DEG;
    X[S_U] = d->start_stw_kn * KNOT;
    X[S_N] = d->start_shaft_rpm / 60.0;
}

fmi2Status model_exit_initialization(ModelInstance *comp) {
    ModelData *d = &comp->data;
    if (!(fabs(d->start_lat_deg) < 85.0)) {
        log_error(comp, "fmi2ExitInitializationMode: start_lat = %g deg is outside (-85, 85)", d->start_lat_deg);
        return fmi2Error;
    }
    if (!(d->h_int_s > 0.0) || !(d->max_thrust_kN >= 0.0) || !(d->max_moment_kNm >= 0.0)) {
        log_error(comp, "fmi2ExitInitializationMode: internal_step must be positive and the maxima not negative");
        return fmi2Error;
    }
    if (d->actuator_mode != 0.0 && d->actuator_mode != 1.0) {
        log_error(comp, "fmi2ExitInitializationMode: actuator_mode = %g must be 0 (propeller_thrust and "
                  "rudder_moment) or 1 (rudder_order and shaft_speed_order)", d->actuator_mode);
        return fmi2Error;
    }
    if (!(d->start_shaft_rpm >= 0.0 && d->start_shaft_rpm <= RPM_MAX)) {
        log_error(comp, "fmi2ExitInitializationMode: start_shaft_speed = %g rpm is outside [0, %g]",
                  d->start_shaft_rpm, RPM_MAX);
        return fmi2Error;
    }
    initial_state(d, d->X);
    return fmi2OK;
}

fmi2Status model_get_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real *value) {
    ModelData *d = &comp->data;
    double X0[S_NSTATES], vn, ve, F[3], thrust;
    const double *X = d->X;
    if (comp->state == InitializationMode) {
        initial_state(d, X0);
        X = X0;
    }
    switch (vr) {
    case vr_lat: *value = X[S_LAT] / DEG; return fmi2OK;
    case vr_lon: *value = X[S_LON] / DEG; return fmi2OK;
    case vr_north_km: *value = X[S_NORTH] / 1e3; return fmi2OK;
    case vr_east_km: *value = X[S_EAST] / 1e3; return fmi2OK;
    case vr_heading: *value = plant_compass_deg(X[S_PSI]); return fmi2OK;
    case vr_stw: *value = X[S_U] / KNOT; return fmi2OK;
    case vr_sway_speed: *value = X[S_V] / KNOT; return fmi2OK;
    case vr_rot: *value = X[S_R] / DEG * 60.0; return fmi2OK;
    case vr_sog:
    case vr_cog:
        over_ground(d, X, &vn, &ve);
        *value = vr == vr_sog ? hypot(vn, ve) / KNOT : plant_compass_deg(atan2(ve, vn));
        return fmi2OK;
    case vr_rudder_position: *value = actuator_mode(d) ? X[S_DELTA] / DEG : 0.0; return fmi2OK;
    case vr_shaft_speed: *value = actuator_mode(d) ? X[S_N] * 60.0 : 0.0; return fmi2OK;
    case vr_shaft_thrust:   /* in the force mode: the surge force applied */
        if (!actuator_mode(d)) {
            *value = plant_clip(d->thrust_kN, -d->max_thrust_kN, d->max_thrust_kN);
            return fmi2OK;
        }
        actuator_loads(X, F, &thrust);
        *value = thrust / 1e3;
        return fmi2OK;
    default:
        *value = *field(d, vr);
        return fmi2OK;
    }
}

fmi2Status model_set_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real value) {
    *field(&comp->data, vr) = value;
    return fmi2OK;
}

/* derivatives in the integrator's form (rk4.h); the inputs are fields of the model data. */
static void s175_derivatives(const void *d, const void *unused, const double *X, double *dX) {
    (void)unused;
    derivatives((const ModelData *)d, X, dX);
}

fmi2Status model_do_step(ModelInstance *comp, double t, double h) {
    ModelData *d = &comp->data;
    return plant_rk4_step(comp, s175_derivatives, d, d->X, S_NSTATES, S_PSI, d->h_int_s, t, h);
}

void model_free_resources(ModelInstance *comp) { (void)comp; }
