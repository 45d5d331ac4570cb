/* KCS plant FMU: start values, get/set by value reference and doStep over the shared
 * dynamics of models/common/kcs_dynamics.h. Equations and sources: readme.md. */
#include "kcs_fmu.h"

#define IN(name) {vr_##name, #name, TypeReal, CausalityInput, VariabilityContinuous}
#define OUT(name) {vr_##name, #name, TypeReal, CausalityOutput, VariabilityContinuous}
#define INITIAL(name) {vr_##name, #name, TypeReal, CausalityParameter, VariabilityFixed}
#define PARAM(name, variability) {vr_##name, #name, TypeReal, CausalityParameter, variability},

const ModelVariable model_variables[N_VARIABLES] = {
    IN(tau_u), IN(tau_r), IN(current_north), IN(current_east), IN(wind_speed),
    IN(wind_direction), IN(hs),
    OUT(x), OUT(y), OUT(psi), OUT(u), OUT(v), OUT(r), OUT(sog), OUT(cog),
    INITIAL(x0), INITIAL(y0), INITIAL(psi0), INITIAL(u0), INITIAL(v0), INITIAL(r0),
    KCS_PARAMETERS(PARAM)
};

/* Storage of every input and parameter (outputs are computed). */
static double *field(ModelData *d, fmi2ValueReference vr) {
    switch (vr) {
    case vr_tau_u: return &d->in.tau_u;
    case vr_tau_r: return &d->in.tau_r;
    case vr_current_north: return &d->in.current_north;
    case vr_current_east: return &d->in.current_east;
    case vr_wind_speed: return &d->in.wind_speed;
    case vr_wind_direction: return &d->in.wind_direction;
    case vr_hs: return &d->in.hs;
    case vr_x0: return &d->X0[KCS_X];
    case vr_y0: return &d->X0[KCS_Y];
    case vr_psi0: return &d->X0[KCS_PSI];
    case vr_u0: return &d->X0[KCS_U];
    case vr_v0: return &d->X0[KCS_V];
    case vr_r0: return &d->X0[KCS_R];
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
    /* before initialisation ends the outputs show the initial state */
    const double *X = comp->state == InitializationMode ? d->X0 : d->X;
    double sog, cog, *f;
    switch (vr) {
    case vr_x: *value = X[KCS_X]; return fmi2OK;
    case vr_y: *value = X[KCS_Y]; return fmi2OK;
    case vr_psi: *value = kcs_wrap_angle(X[KCS_PSI]); return fmi2OK;
    case vr_u: *value = X[KCS_U]; return fmi2OK;
    case vr_v: *value = X[KCS_V]; return fmi2OK;
    case vr_r: *value = X[KCS_R]; return fmi2OK;
    case vr_sog:
    case vr_cog:
        kcs_over_ground(X, &d->in, &sog, &cog);
        *value = vr == vr_sog ? sog : cog;
        return fmi2OK;
    default:
        f = field(d, vr);
        *value = *f;
        return fmi2OK;
    }
}

fmi2Status model_set_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real value) {
    return kcs_set_checked(comp, vr, field(&comp->data, vr), value);
}

fmi2Status model_do_step(ModelInstance *comp, double t, double h) {
    ModelData *d = &comp->data;
    return kcs_step(comp, &d->p, d->X, &d->in, t, h);
}

void model_free_resources(ModelInstance *comp) { (void)comp; }
