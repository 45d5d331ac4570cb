/* KCSVendorB plant FMU: the shared KCS dynamics (models/common/kcs_dynamics.h) behind a
 * vendor interface in kN, kN m, knots and degrees. Every value is converted to SI at the
 * boundary (set/get); the state and the integration are those of the KCS FMU. */
#include "kcs_fmu.h"

#define KNOT 0.514444444444444444 /* m/s per knot (1852 m / 3600 s) */
#define DEG (M_PI / 180.0)        /* rad per degree */
#define KILO 1000.0

#define IN(name) {vr_##name, #name, TypeReal, CausalityInput, VariabilityContinuous}
#define OUT(name) {vr_##name, #name, TypeReal, CausalityOutput, VariabilityContinuous}
#define INITIAL(name) {vr_##name, #name, TypeReal, CausalityParameter, VariabilityFixed}
#define PARAM(name, variability) {vr_##name, #name, TypeReal, CausalityParameter, variability},

const ModelVariable model_variables[N_VARIABLES] = {
    IN(thrust_kN), IN(yaw_moment_kNm), IN(current_n_kn), IN(current_e_kn), IN(wind_speed_kn),
    IN(wind_from_deg), IN(sig_wave_height_m),
    OUT(north_m), OUT(east_m), OUT(heading_deg), OUT(surge_speed_kn), OUT(sway_speed_kn),
    OUT(yaw_rate_deg_s), OUT(sog_kn), OUT(cog_deg),
    INITIAL(north0_m), INITIAL(east0_m), INITIAL(heading0_deg), INITIAL(surge0_kn),
    INITIAL(sway0_kn), INITIAL(yaw_rate0_deg_s),
    KCS_PARAMETERS(PARAM)
};

/* SI storage of an input or parameter and the factor from the vendor unit to SI. */
static double *field(ModelData *d, fmi2ValueReference vr, double *to_si) {
    *to_si = 1.0;
    switch (vr) {
    case vr_thrust_kN: *to_si = KILO; return &d->in.tau_u;
    case vr_yaw_moment_kNm: *to_si = KILO; return &d->in.tau_r;
    case vr_current_n_kn: *to_si = KNOT; return &d->in.current_north;
    case vr_current_e_kn: *to_si = KNOT; return &d->in.current_east;
    case vr_wind_speed_kn: *to_si = KNOT; return &d->in.wind_speed;
    case vr_wind_from_deg: *to_si = DEG; return &d->in.wind_direction;
    case vr_sig_wave_height_m: return &d->in.hs;
    case vr_north0_m: return &d->X0[KCS_X];
    case vr_east0_m: return &d->X0[KCS_Y];
    case vr_heading0_deg: *to_si = DEG; return &d->X0[KCS_PSI];
    case vr_surge0_kn: *to_si = KNOT; return &d->X0[KCS_U];
    case vr_sway0_kn: *to_si = KNOT; return &d->X0[KCS_V];
    case vr_yaw_rate0_deg_s: *to_si = DEG; return &d->X0[KCS_R];
#define KCS_CASE(name, variability) case vr_##name: return &d->p.name;
    KCS_PARAMETERS(KCS_CASE)
#undef KCS_CASE
    default: return NULL;
    }
}

void model_set_start_values(ModelInstance *comp) { kcs_start_values(&comp->data); }

fmi2Status model_exit_initialization(ModelInstance *comp) { return kcs_exit_initialization(comp); }

fmi2Status model_get_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real *value) {
    ModelData *d = &comp->data;
    const double *X = comp->state == InitializationMode ? d->X0 : d->X;
    double sog, cog, to_si, *f;
    switch (vr) {
    case vr_north_m: *value = X[KCS_X]; return fmi2OK;
    case vr_east_m: *value = X[KCS_Y]; return fmi2OK;
    case vr_heading_deg: *value = kcs_wrap_angle(X[KCS_PSI]) / DEG; return fmi2OK;
    case vr_surge_speed_kn: *value = X[KCS_U] / KNOT; return fmi2OK;
    case vr_sway_speed_kn: *value = X[KCS_V] / KNOT; return fmi2OK;
    case vr_yaw_rate_deg_s: *value = X[KCS_R] / DEG; return fmi2OK;
    case vr_sog_kn:
    case vr_cog_deg:
        kcs_over_ground(X, &d->in, &sog, &cog);
        *value = vr == vr_sog_kn ? sog / KNOT : cog / DEG;
        return fmi2OK;
    default:
        f = field(d, vr, &to_si);
        *value = *f / to_si;
        return fmi2OK;
    }
}

fmi2Status model_set_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real value) {
    double to_si, *f = field(&comp->data, vr, &to_si);
    return kcs_set_checked(comp, vr, f, value * to_si);
}

fmi2Status model_do_step(ModelInstance *comp, double t, double h) {
    ModelData *d = &comp->data;
    return kcs_step(comp, &d->p, d->X, &d->in, t, h);
}

void model_free_resources(ModelInstance *comp) { (void)comp; }
