/* KVLCC2 plant FMU: the KRISO VLCC tanker (Lpp 320 m, B 58 m, d 20.8 m, Cb 0.810) in surge,
 * sway and yaw, written as a vendor would: MMG hull, propeller and rudder (Yasukawa and
 * Yoshimura 2015), the centre of gravity 11.2 m forward of midship (sway-yaw mass coupling),
 * a rudder that stalls, a steering gear, a diesel engine and shaft with a PI speed governor,
 * position integrated as latitude/longitude on a sphere. Rudder order in degrees and shaft
 * speed order in rpm; with ForceMode = 1 the rudder stays midships and the surge force and yaw
 * moment demands act instead of the propeller's thrust and the rudder's moment. Internally SI;
 * equations and sources in readme.md, derived figures in derive.py. */
#include <math.h>
#include <string.h>

#include "fmu_model.h"
#include "plant_step.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define KNOT (1852.0 / 3600.0)
#define DEG (M_PI / 180.0)
#define EARTH_RADIUS 6371008.8 /* m, the mean sphere */

/* particulars */
static const double LPP = 320.0, BEAM = 58.0, DRAUGHT = 20.8; /* m */
static const double VOLUME = 312600.0, X_G = 11.2;           /* m^3; m, forward of midship */
static const double RHO = 1025.0, RHO_AIR = 1.225, GRAVITY = 9.81;
/* added masses and hull derivatives, non-dimensional (1/2 rho L d; L^2; L^4) */
static const double MX = 0.022, MY = 0.223, JZ = 0.011, K_ZZ = 0.25; /* k_zz / Lpp */
static const double R0 = 7.658504e-3; /* full scale at 15.5 kn (derive.py) */
static const double X_VV = -0.040, X_VR = 0.002, X_RR = 0.011, X_VVVV = 0.771;
static const double Y_V = -0.315, Y_R = 0.083, Y_VVV = -1.607, Y_VVR = 0.379, Y_VRR = -0.391, Y_RRR = 0.008;
static const double N_V = -0.137, N_R = -0.049, N_VVV = -0.030, N_VVR = -0.294, N_VRR = 0.055, N_RRR = -0.013;
/* propeller */
static const double D_P = 9.86, X_P = -0.48, W_P0 = 0.40, T_P = 0.220; /* m; -; -; - */
static const double WAKE_C1 = 2.0, WAKE_C2_PLUS = 1.6, WAKE_C2_MINUS = 1.1;
static const double KT0 = 0.2931, KT1 = -0.2753, KT2 = -0.1385;
static const double KQ0 = 0.0327, KQ1 = -0.0250, KQ2 = -0.0075; /* estimate, readme.md */
/* rudder */
static const double A_R = 112.5, H_R = 15.8;        /* m^2, m */
static const double F_ALPHA = 2.747, EPSILON = 1.09, KAPPA = 0.50, T_R = 0.387;
static const double A_H = 0.312, X_H = -0.464, X_R = -0.5, L_R = -0.710;
static const double GAMMA_R_PLUS = 0.640, GAMMA_R_MINUS = 0.395;
static const double STALL = 27.0 * DEG, STALL_LOSS = 0.35, STALL_WIDTH = 4.0 * DEG;
static const double RUDDER_MAX = 35.0 * DEG, RUDDER_RATE = 2.34 * DEG, RUDDER_GAIN = 1.0; /* rad, rad/s, 1/s */
/* engine, shaft and governor */
static const double SHAFT_INERTIA = 1.2e6;  /* kg m^2: engine, shaft, propeller, entrained water */
static const double TORQUE_MAX = 4.2e6;     /* N m, engine torque limit */
static const double RPS_MAX = 80.0 / 60.0;  /* 1/s */
static const double SETPOINT_RATE = 1.0 / 60.0, SETPOINT_GAIN = 0.5; /* 1/s^2 (1 rpm/s), 1/s */
static const double GOV_KP = 5.0e6, GOV_KI = 2.0e6; /* N m s, N m: per 1/s of speed error */
/* wind and waves */
static const double AREA_FRONTAL = 1200.0, AREA_LATERAL = 4800.0; /* m^2 */
static const double WIND_CX = 0.8, WIND_CY = 0.9, WIND_CN = 0.08;
static const double WAVE_CX = 0.12, WAVE_CY = 0.04, WAVE_CN = 0.004;

#define IN(name) {vr_##name, #name, TypeReal, CausalityInput, VariabilityContinuous}
#define OUT(name) {vr_##name, #name, TypeReal, CausalityOutput, VariabilityContinuous}
#define FIXED(name) {vr_##name, #name, TypeReal, CausalityParameter, VariabilityFixed}
#define TUNABLE(name) {vr_##name, #name, TypeReal, CausalityParameter, VariabilityTunable}

const ModelVariable model_variables[N_VARIABLES] = {
    IN(RudderOrder), IN(ShaftSpeedOrder), IN(SurgeForceDemand), IN(YawMomentDemand),
    IN(CurrentSpeed), IN(CurrentDirection), IN(WindSpeed), IN(WindDirection), IN(WaveHeight),
    OUT(Latitude), OUT(Longitude), OUT(Heading), OUT(SurgeSpeed), OUT(SwaySpeed), OUT(YawRate),
    OUT(SpeedOverGround), OUT(CourseOverGround), OUT(RudderAngle), OUT(ShaftSpeed),
    OUT(PropellerThrust), OUT(ShaftPower),
    FIXED(ForceMode), FIXED(InitialLatitude), FIXED(InitialLongitude), FIXED(InitialHeading),
    FIXED(InitialSpeed), FIXED(InitialShaftSpeed), TUNABLE(MaxSurgeForce), TUNABLE(MaxYawMoment),
    TUNABLE(IntegrationStep),
};

static double *field(ModelData *d, fmi2ValueReference vr) {
    switch (vr) {
    case vr_RudderOrder: return &d->rudder_order_deg;
    case vr_ShaftSpeedOrder: return &d->shaft_order_rpm;
    case vr_SurgeForceDemand: return &d->surge_demand_MN;
    case vr_YawMomentDemand: return &d->yaw_demand_MNm;
    case vr_CurrentSpeed: return &d->current_mps;
    case vr_CurrentDirection: return &d->current_towards_deg;
    case vr_WindSpeed: return &d->wind_mps;
    case vr_WindDirection: return &d->wind_from_deg;
    case vr_WaveHeight: return &d->hs_m;
    case vr_ForceMode: return &d->force_mode;
    case vr_InitialLatitude: return &d->start_lat_deg;
    case vr_InitialLongitude: return &d->start_lon_deg;
    case vr_InitialHeading: return &d->start_heading_deg;
    case vr_InitialSpeed: return &d->start_speed_kn;
    case vr_InitialShaftSpeed: return &d->start_shaft_rpm;
    case vr_MaxSurgeForce: return &d->max_surge_MN;
    case vr_MaxYawMoment: return &d->max_yaw_MNm;
    case vr_IntegrationStep: return &d->h_int_s;
    default: return NULL;
    }
}

/* Rudder normal-force coefficient at the effective angle alpha: the lift slope up to the
 * stall angle, then a loss that grows to STALL_LOSS of the peak over a few degrees. */
static double rudder_normal_coefficient(double alpha) {
    const double a = fabs(alpha), s = alpha < 0.0 ? -1.0 : 1.0;
    if (a <= STALL) return F_ALPHA * sin(alpha);
    return s * F_ALPHA * sin(STALL) * (1.0 - STALL_LOSS * (1.0 - exp(-(a - STALL) / STALL_WIDTH)));
}

static int force_mode(const ModelData *d) { return d->force_mode > 0.5; }

/* Loads [X, Y, N about midship] (N, N, N m) of hull, propeller, rudder (or the force
 * demands), wind and waves; the propeller thrust T (N) and torque Q (N m). */
static void loads(const ModelData *d, const double X[S_NSTATES], double F[3], double *T, double *Q) {
    const double psi = X[S_PSI], u = X[S_U], v = X[S_V], r = X[S_R];
    const double U = hypot(u, v), qh = 0.5 * RHO * LPP * DRAUGHT * U * U;
    const double vp = U > 1e-6 ? v / U : 0.0, rp = U > 1e-6 ? r * LPP / U : 0.0;
    const double beta = U > 1e-6 ? atan2(-v, u) : 0.0;
    const double beta_p = beta - X_P * rp, beta_r = beta - L_R * rp;
    const double c2 = beta_p > 0.0 ? WAKE_C2_PLUS : WAKE_C2_MINUS;
    const double ua = u * (1.0 - W_P0) * (1.0 + (1.0 - exp(-WAKE_C1 * fabs(beta_p))) * (c2 - 1.0));
    const double n = force_mode(d) ? 0.0 : X[S_N], nd = n * D_P;
    const double delta = force_mode(d) ? 0.0 : X[S_DELTA];
    double thrust, loading, slip, inner, uR, vR, FN, eta = D_P / H_R;
    if (force_mode(d)) {
        thrust = fmax(plant_clip(d->surge_demand_MN, -d->max_surge_MN, d->max_surge_MN) * 1e6, 0.0) / (1.0 - T_P);
        *Q = 0.0;
    } else {
        thrust = RHO * D_P * D_P * (KT0 * nd * nd + KT1 * nd * ua + KT2 * ua * ua);
        *Q = RHO * D_P * D_P * D_P * (KQ0 * nd * nd + KQ1 * nd * ua + KQ2 * ua * ua);
    }
    *T = thrust;
    loading = 8.0 * thrust / (M_PI * RHO * D_P * D_P);
    slip = sqrt(ua * ua + (loading > 0.0 ? loading : 0.0));
    inner = ua + KAPPA * (slip - ua);
    uR = EPSILON * sqrt(eta * inner * inner + (1.0 - eta) * ua * ua);
    vR = U * (beta_r >= 0.0 ? GAMMA_R_PLUS : GAMMA_R_MINUS) * beta_r;
    FN = 0.5 * RHO * A_R * (uR * uR + vR * vR) * rudder_normal_coefficient(delta - atan2(vR, uR));
    F[0] = qh * (-R0 + X_VV * vp * vp + X_VR * vp * rp + X_RR * rp * rp + X_VVVV * vp * vp * vp * vp)
           - (1.0 - T_R) * FN * sin(delta);
    F[1] = qh * (Y_V * vp + Y_R * rp + Y_VVV * vp * vp * vp + Y_VVR * vp * vp * rp + Y_VRR * vp * rp * rp
                 + Y_RRR * rp * rp * rp) - (1.0 + A_H) * FN * cos(delta);
    F[2] = qh * LPP * (N_V * vp + N_R * rp + N_VVV * vp * vp * vp + N_VVR * vp * vp * rp + N_VRR * vp * rp * rp
                       + N_RRR * rp * rp * rp) - (X_R + A_H * X_H) * LPP * FN * cos(delta);
    if (force_mode(d)) {
        F[0] += plant_clip(d->surge_demand_MN, -d->max_surge_MN, d->max_surge_MN) * 1e6;
        F[2] += plant_clip(d->yaw_demand_MNm, -d->max_yaw_MNm, d->max_yaw_MNm) * 1e6;
    } else {
        F[0] += (1.0 - T_P) * thrust;
    }
    {   /* wind from WindDirection, waves from the wind, relative to the water */
        const double c = cos(psi), s = sin(psi), from = d->wind_from_deg * DEG, ws = d->wind_mps;
        const double set = d->current_towards_deg * DEG, cur = d->current_mps;
        const double vn = u * c - v * s + cur * cos(set), ve = u * s + v * c + cur * sin(set);
        const double rel_n = vn + ws * cos(from), rel_e = ve + ws * sin(from);
        const double u_rw = c * rel_n + s * rel_e, v_rw = -s * rel_n + c * rel_e;
        const double gamma = atan2(v_rw, u_rw), qa = 0.5 * RHO_AIR * (u_rw * u_rw + v_rw * v_rw);
        const double gamma_w = from - psi, qw = 0.5 * RHO * GRAVITY * d->hs_m * d->hs_m;
        F[0] += -qa * WIND_CX * AREA_FRONTAL * cos(gamma) - qw * WAVE_CX * BEAM * cos(gamma_w);
        F[1] += -qa * WIND_CY * AREA_LATERAL * sin(gamma) - qw * WAVE_CY * LPP * sin(gamma_w);
        F[2] += -qa * WIND_CN * AREA_LATERAL * LPP * sin(2.0 * gamma) - qw * WAVE_CN * LPP * LPP * sin(2.0 * gamma_w);
    }
}

/* Engine torque (N m) of the PI governor at the state X: proportional plus integral part,
 * within [0, TORQUE_MAX] (the engine neither brakes nor exceeds its torque limit). */
static double engine_torque(const double X[S_NSTATES]) {
    return plant_clip(GOV_KP * (X[S_NREF] - X[S_N]) + X[S_GOV], 0.0, TORQUE_MAX);
}

static void derivatives(const ModelData *d, const double X[S_NSTATES], double dX[S_NSTATES]) {
    const double m = RHO * VOLUME, q = 0.5 * RHO * LPP * DRAUGHT;
    const double m11 = m + MX * q * LPP, m22 = m + MY * q * LPP, m23 = X_G * m;
    const double m33 = m * K_ZZ * K_ZZ * LPP * LPP + X_G * X_G * m + JZ * q * LPP * LPP * LPP;
    const double psi = X[S_PSI], u = X[S_U], v = X[S_V], r = X[S_R];
    const double set = d->current_towards_deg * DEG, cur = d->current_mps;
    const double vn = u * cos(psi) - v * sin(psi) + cur * cos(set);
    const double ve = u * sin(psi) + v * cos(psi) + cur * sin(set);
    const double delta_cmd = plant_clip(d->rudder_order_deg * DEG, -RUDDER_MAX, RUDDER_MAX);
    const double n_cmd = plant_clip(d->shaft_order_rpm / 60.0, 0.0, RPS_MAX);
    double F[3], T, Q, b1, b2, det, error, q_engine, raw;
    loads(d, X, F, &T, &Q);
    /* [m22, m23; m23, m33] [vdot; rdot] = [Y - m11 u r; N - m23 u r] */
    b1 = F[1] - m11 * u * r;
    b2 = F[2] - m23 * u * r;
    det = m22 * m33 - m23 * m23;
    dX[S_LAT] = vn / EARTH_RADIUS;
    dX[S_LON] = ve / (EARTH_RADIUS * cos(X[S_LAT]));
    dX[S_PSI] = r;
    dX[S_U] = (F[0] + m22 * v * r + m23 * r * r) / m11;
    dX[S_V] = (m33 * b1 - m23 * b2) / det;
    dX[S_R] = (m22 * b2 - m23 * b1) / det;
    if (force_mode(d)) {
        dX[S_DELTA] = dX[S_N] = dX[S_NREF] = dX[S_GOV] = 0.0;
        return;
    }
    dX[S_DELTA] = plant_clip(RUDDER_GAIN * (delta_cmd - X[S_DELTA]), -RUDDER_RATE, RUDDER_RATE);
    dX[S_NREF] = plant_clip(SETPOINT_GAIN * (n_cmd - X[S_NREF]), -SETPOINT_RATE, SETPOINT_RATE);
    error = X[S_NREF] - X[S_N];
    raw = GOV_KP * error + X[S_GOV];
    q_engine = engine_torque(X);
    /* integrate only while the torque is not limited, or when the error leads back inside */
    dX[S_GOV] = (raw == q_engine || (raw > TORQUE_MAX && error < 0.0) || (raw < 0.0 && error > 0.0))
                    ? GOV_KI * error : 0.0;
    dX[S_N] = (q_engine - Q) / (2.0 * M_PI * SHAFT_INERTIA);
}

void model_set_start_values(ModelInstance *comp) {
    ModelData *d = &comp->data;
    memset(d, 0, sizeof *d);
    d->max_surge_MN = 2.35;   /* net thrust at 80 rpm and 15.5 kn (derive.py) */
    d->max_yaw_MNm = 587.0;   /* rudder at its stall angle at 15.5 kn and 71 rpm (derive.py) */
    d->h_int_s = 0.25;
}

static void initial_state(const ModelData *d, double X[S_NSTATES]) {
    double F[3], T, Q;
    memset(X, 0, S_NSTATES * sizeof X[0]);
    X[S_LAT] = d->start_lat_deg * DEG;
    X[S_LON] = d->start_lon_deg * DEG;
    X[S_PSI] = d->start_heading_deg * DEG;
    X[S_U] = d->start_speed_kn * KNOT;
    X[S_N] = X[S_NREF] = d->start_shaft_rpm / 60.0;
    loads(d, X, F, &T, &Q);
    X[S_GOV] = plant_clip(Q, 0.0, TORQUE_MAX); /* the governor starts holding the shaft speed */
}

fmi2Status model_exit_initialization(ModelInstance *comp) {
    ModelData *d = &comp->data;
    if (!(fabs(d->start_lat_deg) < 85.0)) {
        log_error(comp, "fmi2ExitInitializationMode: InitialLatitude = %g deg is outside (-85, 85)", d->start_lat_deg);
        return fmi2Error;
    }
    if (d->force_mode != 0.0 && d->force_mode != 1.0) {
        log_error(comp, "fmi2ExitInitializationMode: ForceMode = %g must be 0 (rudder and shaft) or 1 (forces)",
                  d->force_mode);
        return fmi2Error;
    }
    if (!(d->h_int_s > 0.0) || !(d->max_surge_MN >= 0.0) || !(d->max_yaw_MNm >= 0.0)) {
        log_error(comp, "fmi2ExitInitializationMode: IntegrationStep must be positive and MaxSurgeForce, "
                  "MaxYawMoment not negative");
        return fmi2Error;
    }
    if (!(d->start_shaft_rpm >= 0.0 && d->start_shaft_rpm <= RPS_MAX * 60.0)) {
        log_error(comp, "fmi2ExitInitializationMode: InitialShaftSpeed = %g rpm is outside [0, %g]",
                  d->start_shaft_rpm, RPS_MAX * 60.0);
        return fmi2Error;
    }
    initial_state(d, d->X);
    return fmi2OK;
}

fmi2Status model_get_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real *value) {
    ModelData *d = &comp->data;
    double X0[S_NSTATES], F[3], T, Q, vn, ve;
    const double *X = d->X;
    if (comp->state == InitializationMode) {
        initial_state(d, X0);
        X = X0;
    }
    vn = X[S_U] * cos(X[S_PSI]) - X[S_V] * sin(X[S_PSI]) + d->current_mps * cos(d->current_towards_deg * DEG);
    ve = X[S_U] * sin(X[S_PSI]) + X[S_V] * cos(X[S_PSI]) + d->current_mps * sin(d->current_towards_deg * DEG);
    switch (vr) {
    case vr_Latitude: *value = X[S_LAT] / DEG; return fmi2OK;
    case vr_Longitude: *value = X[S_LON] / DEG; return fmi2OK;
    case vr_Heading: *value = plant_compass_deg(X[S_PSI]); return fmi2OK;
    case vr_SurgeSpeed: *value = X[S_U] / KNOT; return fmi2OK;
    case vr_SwaySpeed: *value = X[S_V] / KNOT; return fmi2OK;
    case vr_YawRate: *value = X[S_R] / DEG; return fmi2OK;
    case vr_SpeedOverGround: *value = hypot(vn, ve) / KNOT; return fmi2OK;
    case vr_CourseOverGround: *value = plant_compass_deg(atan2(ve, vn)); return fmi2OK;
    case vr_RudderAngle: *value = force_mode(d) ? 0.0 : X[S_DELTA] / DEG; return fmi2OK;
    case vr_ShaftSpeed: *value = force_mode(d) ? 0.0 : X[S_N] * 60.0; return fmi2OK;
    case vr_PropellerThrust:
    case vr_ShaftPower:
        loads(d, X, F, &T, &Q);
        *value = vr == vr_PropellerThrust ? T / 1e3 : 2.0 * M_PI * X[S_N] * Q / 1e3;
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
static void kvlcc2_derivatives(const void *d, const void *unused, const double *X, double *dX) {
    (void)unused;
    derivatives((const ModelData *)d, X, dX);
}

fmi2Status model_do_step(ModelInstance *comp, double t, double h) {
    ModelData *d = &comp->data;
    return plant_rk4_step(comp, kvlcc2_derivatives, d, d->X, S_NSTATES, S_PSI, d->h_int_s, t, h);
}

void model_free_resources(ModelInstance *comp) { (void)comp; }
