/* Actuator-level KCS plant FMU (MMG form): start values, get/set by value reference and
 * doStep over models/KCSMMG/mmg_dynamics.h. Equations and sources: readme.md. */
#include "fmu_model.h"

#define IN(name) {vr_##name, #name, TypeReal, CausalityInput, VariabilityContinuous}
#define OUT(name) {vr_##name, #name, TypeReal, CausalityOutput, VariabilityContinuous}
#define INITIAL(name) {vr_##name, #name, TypeReal, CausalityParameter, VariabilityFixed}
#define PARAM(name, variability) {vr_##name, #name, TypeReal, CausalityParameter, variability},

const ModelVariable model_variables[N_VARIABLES] = {
    IN(rudder_angle_cmd), IN(propeller_rps_cmd), IN(current_north), IN(current_east),
    IN(wind_speed), IN(wind_direction), IN(hs),
    OUT(x), OUT(y), OUT(psi), OUT(u), OUT(v), OUT(r), OUT(sog), OUT(cog), OUT(rudder_angle),
    OUT(propeller_rps), OUT(thrust), OUT(delivered_power),
    INITIAL(x0), INITIAL(y0), INITIAL(psi0), INITIAL(u0), INITIAL(v0), INITIAL(r0),
    INITIAL(rudder_angle0), INITIAL(propeller_rps0),
    MMG_PARAMETERS(PARAM)
};

/* Storage of every input and parameter (outputs are computed). */
static double *field(ModelData *d, fmi2ValueReference vr) {
    switch (vr) {
    case vr_rudder_angle_cmd: return &d->in.rudder_angle_cmd;
    case vr_propeller_rps_cmd: return &d->in.propeller_rps_cmd;
    case vr_current_north: return &d->in.current_north;
    case vr_current_east: return &d->in.current_east;
    case vr_wind_speed: return &d->in.wind_speed;
    case vr_wind_direction: return &d->in.wind_direction;
    case vr_hs: return &d->in.hs;
    case vr_x0: return &d->X0[MMG_X];
    case vr_y0: return &d->X0[MMG_Y];
    case vr_psi0: return &d->X0[MMG_PSI];
    case vr_u0: return &d->X0[MMG_U];
    case vr_v0: return &d->X0[MMG_V];
    case vr_r0: return &d->X0[MMG_R];
    case vr_rudder_angle0: return &d->X0[MMG_DELTA];
    case vr_propeller_rps0: return &d->X0[MMG_N];
#define MMG_CASE(name, variability) case vr_##name: return &d->p.name;
    MMG_PARAMETERS(MMG_CASE)
#undef MMG_CASE
    default: return NULL;
    }
}

void model_set_start_values(ModelInstance *comp) {
    ModelData *d = &comp->data;
    int i;
    mmg_default_parameters(&d->p);
    d->in = (MmgInputs){0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    for (i = 0; i < MMG_NSTATES; i++) d->X0[i] = d->X[i] = 0.0;
}

fmi2Status model_exit_initialization(ModelInstance *comp) {
    ModelData *d = &comp->data;
    const char *bad = mmg_invalid_parameter(&d->p);
    int i;
    if (bad) {
        log_error(comp, "parameter %s has an invalid value", bad);
        return fmi2Error;
    }
    if (fabs(d->X0[MMG_DELTA]) > d->p.rudder_max || d->X0[MMG_N] < 0.0 || d->X0[MMG_N] > d->p.propeller_rps_max) {
        log_error(comp, "rudder_angle0 = %g rad or propeller_rps0 = %g 1/s "
                  "outside the actuator range", d->X0[MMG_DELTA], d->X0[MMG_N]);
        return fmi2Error;
    }
    for (i = 0; i < MMG_NSTATES; i++) d->X[i] = d->X0[i];
    d->X[MMG_PSI] = kcs_wrap_angle(d->X[MMG_PSI]);
    return fmi2OK;
}

fmi2Status model_get_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real *value) {
    ModelData *d = &comp->data;
    /* before initialisation ends the outputs show the initial state */
    const double *X = comp->state == InitializationMode ? d->X0 : d->X;
    double F[3];
    MmgReport report;
    switch (vr) {
    case vr_x: *value = X[MMG_X]; return fmi2OK;
    case vr_y: *value = X[MMG_Y]; return fmi2OK;
    case vr_psi: *value = kcs_wrap_angle(X[MMG_PSI]); return fmi2OK;
    case vr_u: *value = X[MMG_U]; return fmi2OK;
    case vr_v: *value = X[MMG_V]; return fmi2OK;
    case vr_r: *value = X[MMG_R]; return fmi2OK;
    case vr_rudder_angle: *value = X[MMG_DELTA]; return fmi2OK;
    case vr_propeller_rps: *value = X[MMG_N]; return fmi2OK;
    case vr_sog:
    case vr_cog: {
        const double n = X[MMG_U] * cos(X[MMG_PSI]) - X[MMG_V] * sin(X[MMG_PSI]) + d->in.current_north;
        const double e = X[MMG_U] * sin(X[MMG_PSI]) + X[MMG_V] * cos(X[MMG_PSI]) + d->in.current_east;
        *value = vr == vr_sog ? hypot(n, e) : kcs_wrap_angle(atan2(e, n));
        return fmi2OK;
    }
    case vr_thrust:
    case vr_delivered_power:
        mmg_forces(&d->p, X[MMG_U], X[MMG_V], X[MMG_R], X[MMG_DELTA], X[MMG_N], F, &report);
        *value = vr == vr_thrust ? report.thrust : report.delivered_power;
        return fmi2OK;
    default:
        *value = *field(d, vr);
        return fmi2OK;
    }
}

fmi2Status model_set_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real value) {
    ModelData *d = &comp->data;
    double *f = field(d, vr), old = *f;
    *f = value;
    /* a tunable parameter changed during the run must keep the model meaningful */
    if (comp->state == StepComplete && vr >= vr_lpp) {
        const char *bad = mmg_invalid_parameter(&d->p);
        if (bad) {
            *f = old;
            log_error(comp, "%s (value reference %u) = %g makes %s invalid",
                      model_variables[vr].name, (unsigned)vr, value, bad);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status model_do_step(ModelInstance *comp, double t, double h) {
    ModelData *d = &comp->data;
    if (mmg_integrate(&d->p, d->X, &d->in, h) != 0) {
        log_error(comp, "the state became non-finite in the step from t = %g s", t);
        return fmi2Error;
    }
    return fmi2OK;
}

void model_free_resources(ModelInstance *comp) { (void)comp; }
