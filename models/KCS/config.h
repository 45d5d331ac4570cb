/* Identity of the KCS plant FMU: identifier, token, value references, model data. */
#ifndef CONFIG_H
#define CONFIG_H

#include "kcs_dynamics.h"

#define MODEL_IDENTIFIER KCS
#define MODEL_IDENTIFIER_STRING "KCS"
#define INSTANTIATION_TOKEN "{6f1c2a8e-3b7d-4c1e-9a55-0d4e7b2f9c11}"
#define MODEL_CAN_GET_SET_STATE 1
#define MODEL_HAS_STRINGS 0

typedef enum {
    /* inputs */
    vr_tau_u, vr_tau_r, vr_current_north, vr_current_east, vr_wind_speed, vr_wind_direction,
    vr_hs,
    /* outputs */
    vr_x, vr_y, vr_psi, vr_u, vr_v, vr_r, vr_sog, vr_cog,
    /* initial state (fixed parameters) */
    vr_x0, vr_y0, vr_psi0, vr_u0, vr_v0, vr_r0,
    /* plant parameters, in the order of KCS_PARAMETERS */
#define KCS_VR(name, variability) vr_##name,
    KCS_PARAMETERS(KCS_VR)
#undef KCS_VR
    N_VARIABLES
} ValueReference;

typedef struct {
    KcsParameters p;
    KcsInputs in;              /* SI */
    double X[KCS_NSTATES];     /* x, y m; psi rad; u, v m/s; r rad/s */
    double X0[KCS_NSTATES];    /* initial state, same units */
} ModelData;

#endif
