/* S175 plant FMU: the ITTC S-175 container ship (Lpp 175 m, B 25.4 m, T 8.5 m, Cb 0.572) in
 * surge, sway and yaw, written as a vendor would: its own variable names and units, position
 * as latitude/longitude on the WGS84 ellipsoid, a quadratic hull resistance. Coefficients:
 * models/S175/derive.py and readme.md. Internally SI. */
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
    default: return NULL;
    }
}

static double clamp(double value, double bound) {
    return value > bound ? bound : (value < -bound ? -bound : value);
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
    const double tau_u = clamp(d->thrust_kN, d->max_thrust_kN) * 1e3;
    const double tau_r = clamp(d->moment_kNm, d->max_moment_kNm) * 1e3;
    const double sin_lat = sin(X[S_LAT]), w = 1.0 - WGS84_E2 * sin_lat * sin_lat;
    const double radius_m = WGS84_A * (1.0 - WGS84_E2) / (w * sqrt(w)); /* meridian */
    const double radius_n = WGS84_A / sqrt(w);                         /* prime vertical */
    double vn, ve, wind[3];
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
    dX[S_V] = (-M11 * u * r - D22 * v - D23 * r + wind[1]) / M22;
    dX[S_R] = ((M11 - M22) * u * v - D32 * v - D33 * r + tau_r + wind[2]) / M33;
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
    initial_state(d, d->X);
    return fmi2OK;
}

fmi2Status model_get_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real *value) {
    ModelData *d = &comp->data;
    double X0[S_NSTATES], vn, ve;
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
