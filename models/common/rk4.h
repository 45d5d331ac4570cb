/* The one integrator of every model: the classical fourth-order Runge-Kutta method over a
 * model's derivative function, with the inputs held over the communication step.
 *
 * rk4_advance() covers `duration` seconds in substeps of h_int; the last substep ends exactly
 * at the communication point, and a sliver below 1e-6 h_int is merged into the step before
 * it.  The model keeps what is its own (saturating inputs beforehand, wrapping the heading
 * and checking the state afterwards). */
#ifndef RK4_H
#define RK4_H

#include <math.h>

/* Largest state a model may integrate here (the MMG plant has 8). */
#define RK4_MAX_STATES 16

/* dX = f(X) for the model `model` with its inputs `inputs` (both passed through untouched). */
typedef void (*rk4_derivatives)(const void *model, const void *inputs, const double *X, double *dX);

/* One RK4 step of h seconds of the n states X (n <= RK4_MAX_STATES). */
static inline void rk4_step(rk4_derivatives f, const void *model, const void *inputs, double *X, int n,
                            double h) {
    double k1[RK4_MAX_STATES], k2[RK4_MAX_STATES], k3[RK4_MAX_STATES], k4[RK4_MAX_STATES];
    double Xt[RK4_MAX_STATES];
    int i;
    f(model, inputs, X, k1);
    for (i = 0; i < n; i++) Xt[i] = X[i] + 0.5 * h * k1[i];
    f(model, inputs, Xt, k2);
    for (i = 0; i < n; i++) Xt[i] = X[i] + 0.5 * h * k2[i];
    f(model, inputs, Xt, k3);
    for (i = 0; i < n; i++) Xt[i] = X[i] + h * k3[i];
    f(model, inputs, Xt, k4);
    for (i = 0; i < n; i++) X[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

/* Advances X over `duration` seconds in RK4 substeps of h_int (see above). */
static inline void rk4_advance(rk4_derivatives f, const void *model, const void *inputs, double *X, int n,
                               double h_int, double duration) {
    double remaining = duration;
    while (remaining > 0.0) {
        const double h = h_int >= remaining - 1e-6 * h_int ? remaining : h_int;
        rk4_step(f, model, inputs, X, n, h);
        remaining -= h;
    }
}

/* 1 when all n states X are finite (a model checks this after each communication step). */
static inline int rk4_finite(const double *X, int n) {
    int i;
    for (i = 0; i < n; i++)
        if (!isfinite(X[i])) return 0;
    return 1;
}

#endif /* RK4_H */
