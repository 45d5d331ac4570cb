/* One NMPC solve of an acados OCP solver in one call: the warm start, the parameters and the
 * bounds of every stage set, the SQP run, the plan and its statistics read back.
 *
 * From Python each acados setter is a ctypes call (a few microseconds each, some 130 per
 * solve for N = 15); here the loops over the stages run in C.  The solver's own functions are
 * passed as pointers, so this file is compiled once per problem beside the generated solver
 * and knows nothing of its name.
 *
 * Layout (row-major, one row per stage): x (N+1) x nx, u N x nu, p (N+1) x np; stage 0's
 * state bounds lbx0/ubx0 (nx: every state fixed), the later stages' nbx per stage in lbx/ubx
 * (N rows), the inputs' nbu per stage in lbu/ubu (N rows).  info: status, SQP iterations, the
 * solver's own time [s], the cost, residuals (stationarity, equalities, inequalities,
 * complementarity).
 */
#include "acados_c/ocp_nlp_interface.h"

typedef int (*update_params_fn)(void *capsule, int stage, double *p, int np);
typedef int (*solve_fn)(void *capsule);

int rhnc_acados_step(void *capsule, update_params_fn update_params, solve_fn solve, ocp_nlp_config *config,
                     ocp_nlp_dims *dims, ocp_nlp_in *in, ocp_nlp_out *out, ocp_nlp_solver *solver,
                     int N, int nx, int nu, int np, int nbx, int nbu, double *x, double *u, double *p,
                     double *lbx0, double *ubx0, double *lbx, double *ubx, double *lbu, double *ubu,
                     double *info)
{
    int k, iterations = 0;
    for (k = 0; k <= N; k++) {
        ocp_nlp_out_set(config, dims, out, k, "x", x + k * nx);
        update_params(capsule, k, p + k * np, np);
    }
    for (k = 0; k < N; k++) {
        ocp_nlp_out_set(config, dims, out, k, "u", u + k * nu);
        ocp_nlp_constraints_model_set(config, dims, in, k, "lbu", lbu + k * nbu);
        ocp_nlp_constraints_model_set(config, dims, in, k, "ubu", ubu + k * nbu);
    }
    ocp_nlp_constraints_model_set(config, dims, in, 0, "lbx", lbx0);
    ocp_nlp_constraints_model_set(config, dims, in, 0, "ubx", ubx0);
    for (k = 1; k <= N; k++) {
        ocp_nlp_constraints_model_set(config, dims, in, k, "lbx", lbx + (k - 1) * nbx);
        ocp_nlp_constraints_model_set(config, dims, in, k, "ubx", ubx + (k - 1) * nbx);
    }
    int status = solve(capsule);
    for (k = 0; k <= N; k++)
        ocp_nlp_out_get(config, dims, out, k, "x", x + k * nx);
    for (k = 0; k < N; k++)
        ocp_nlp_out_get(config, dims, out, k, "u", u + k * nu);
    ocp_nlp_get(config, solver, "sqp_iter", &iterations);
    info[0] = status;
    info[1] = iterations;
    ocp_nlp_get(config, solver, "time_tot", info + 2);
    ocp_nlp_eval_cost(solver, in, out);
    ocp_nlp_get(config, solver, "cost_value", info + 3);
    ocp_nlp_get(config, solver, "res_stat", info + 4);
    ocp_nlp_get(config, solver, "res_eq", info + 5);
    ocp_nlp_get(config, solver, "res_ineq", info + 6);
    ocp_nlp_get(config, solver, "res_comp", info + 7);
    return status;
}
