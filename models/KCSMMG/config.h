/* Identity of the actuator-level KCS plant FMU (MMG form): identifier, token, value
 * references, model data. */
#ifndef CONFIG_H
#define CONFIG_H

#include "mmg_dynamics.h"

#define MODEL_IDENTIFIER KCSMMG
#define MODEL_IDENTIFIER_STRING "KCSMMG"
#define INSTANTIATION_TOKEN "{3b8d2e61-7c4f-4a19-b0e5-5f2a9c7d1e84}"
#define MODEL_CAN_GET_SET_STATE 1
#define MODEL_HAS_STRINGS 0

typedef enum {
    /* inputs */
    vr_rudder_angle_cmd, vr_propeller_rps_cmd, vr_current_north, vr_current_east,
    vr_wind_speed, vr_wind_direction, vr_hs,
    /* outputs */
    vr_x, vr_y, vr_psi, vr_u, vr_v, vr_r, vr_sog, vr_cog, vr_rudder_angle, vr_propeller_rps,
    vr_thrust, vr_delivered_power,
    /* initial state (fixed parameters) */
    vr_x0, vr_y0, vr_psi0, vr_u0, vr_v0, vr_r0, vr_rudder_angle0, vr_propeller_rps0,
    /* plant parameters, in the order of MMG_PARAMETERS */
#define MMG_VR(name, variability) vr_##name,
    MMG_PARAMETERS(MMG_VR)
#undef MMG_VR
    N_VARIABLES
} ValueReference;

typedef struct {
    MmgParameters p;
    MmgInputs in;              /* SI */
    double X[MMG_NSTATES];     /* x, y m; psi rad; u, v m/s; r rad/s; rudder rad; rps 1/s */
    double X0[MMG_NSTATES];    /* initial state, same units */
} ModelData;

#endif
