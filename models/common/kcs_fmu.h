/* Glue shared by the plant FMUs built on kcs_dynamics.h (KCS, KCSVendorB): their start values,
 * the end of initialisation, the checks on a parameter set through fmi2SetReal and the
 * communication step. Both keep the same ModelData (p, in, X, X0, all SI) in config.h. The variables are matched by
 * their names, which both models share for the KCS parameters (h_int, tau_u_max, ...).
 */
#ifndef KCS_FMU_H
#define KCS_FMU_H

#include <string.h>

#include "fmu_model.h"
#include "kcs_dynamics.h"

/* Start values (fmi2Instantiate, fmi2Reset): the default parameter set, inputs and state zero. */
static inline void kcs_start_values(ModelData *d) {
    kcs_default_parameters(&d->p);
    d->in = (KcsInputs){0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    for (int i = 0; i < KCS_NSTATES; i++) d->X0[i] = d->X[i] = 0.0;
}

/* End of initialisation: the parameter set checked, the state set to the initial one. */
static inline fmi2Status kcs_exit_initialization(ModelInstance *comp) {
    ModelData *d = &comp->data;
    const char *bad = kcs_invalid_parameter(&d->p);
    if (bad) {
        log_error(comp, "parameter %s has an invalid value", bad);
        return fmi2Error;
    }
    for (int i = 0; i < KCS_NSTATES; i++) d->X[i] = d->X0[i];
    d->X[KCS_PSI] = kcs_wrap_angle(d->X[KCS_PSI]);
    return fmi2OK;
}

/* Store si_value (already in SI) in *field after the checks a plant parameter needs. */
static inline fmi2Status kcs_set_checked(ModelInstance *comp, fmi2ValueReference vr, double *field,
                                         double si_value) {
    const char *name = model_variables[vr].name;
    if (strcmp(name, "h_int") == 0 && !(si_value > 0.0)) {
        log_error(comp, "h_int (value reference %u) = %g must be positive", (unsigned)vr,
                  si_value);
        return fmi2Error;
    }
    if ((strcmp(name, "tau_u_max") == 0 || strcmp(name, "tau_r_max") == 0) && si_value < 0.0) {
        log_error(comp, "%s (value reference %u) = %g must not be negative", name,
                  (unsigned)vr, si_value);
        return fmi2Error;
    }
    *field = si_value;
    return fmi2OK;
}

/* Integrate the plant over one communication step [t, t + h]. */
static inline fmi2Status kcs_step(ModelInstance *comp, const KcsParameters *p, double X[KCS_NSTATES],
                                  const KcsInputs *in, double t, double h) {
    if (kcs_integrate(p, X, in, h) != 0) {
        log_error(comp, "the state became non-finite in the step from t = %g s", t);
        return fmi2Error;
    }
    return fmi2OK;
}

#endif
