/* What the plant FMUs with equations of their own (KVLCC2, S175) share besides the FMI layer:
 * the communication step over rk4.h, the compass heading of their outputs and the limit of a
 * value to a range. Their equations
 * and interfaces stay in their folders. */
#ifndef PLANT_STEP_H
#define PLANT_STEP_H

#include <math.h>

#include "fmu_model.h"
#include "rk4.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Advances the model's n states X over the communication step [t, t + h] in RK4 substeps of
 * h_int (rk4.h; derivatives f(model, NULL, X, dX)), the heading X[psi] (rad) kept within one
 * turn; fmi2Error, logged with t, when a state became non-finite. */
static inline fmi2Status plant_rk4_step(ModelInstance *comp, rk4_derivatives f, const void *model, double *X,
                                        int n, int psi, double h_int, double t, double h) {
    rk4_advance(f, model, NULL, X, n, h_int, h);
    X[psi] = fmod(X[psi], 2.0 * M_PI);
    if (!rk4_finite(X, n)) {
        log_error(comp, "fmi2DoStep: the state became non-finite in the step from t = %g s", t);
        return fmi2Error;
    }
    return fmi2OK;
}

/* A heading (rad) as a compass heading in [0, 360) degrees. */
static inline double plant_compass_deg(double angle) {
    double deg = fmod(angle / (M_PI / 180.0), 360.0);
    return deg < 0.0 ? deg + 360.0 : deg;
}

/* value limited to [low, high]. */
static inline double plant_clip(double value, double low, double high) {
    return value > high ? high : (value < low ? low : value);
}

#endif /* PLANT_STEP_H */
