/* Identity of the KCSVendorB plant FMU: the KCS dynamics behind another vendor's interface
 * (other variable names, kN / knots / degrees). */
#ifndef CONFIG_H
#define CONFIG_H

#include "kcs_dynamics.h"

#define MODEL_IDENTIFIER KCSVendorB
#define MODEL_IDENTIFIER_STRING "KCSVendorB"
#define INSTANTIATION_TOKEN "{b2d7e4a1-58c3-4f0b-8e6d-3a9c1f7e2b40}"
#define MODEL_CAN_GET_SET_STATE 1
#define MODEL_HAS_STRINGS 0

typedef enum {
    /* inputs */
    vr_thrust_kN, vr_yaw_moment_kNm, vr_current_n_kn, vr_current_e_kn, vr_wind_speed_kn,
    vr_wind_from_deg, vr_sig_wave_height_m,
    /* outputs */
    vr_north_m, vr_east_m, vr_heading_deg, vr_surge_speed_kn, vr_sway_speed_kn,
    vr_yaw_rate_deg_s, vr_sog_kn, vr_cog_deg,
    /* initial state (fixed parameters) */
    vr_north0_m, vr_east0_m, vr_heading0_deg, vr_surge0_kn, vr_sway0_kn, vr_yaw_rate0_deg_s,
    /* plant parameters, SI, same names as KCS */
#define KCS_VR(name, variability) vr_##name,
    KCS_PARAMETERS(KCS_VR)
#undef KCS_VR
    N_VARIABLES
} ValueReference;

typedef struct {
    KcsParameters p;
    KcsInputs in;              /* SI, converted on set */
    double X[KCS_NSTATES];     /* SI state */
    double X0[KCS_NSTATES];    /* SI initial state */
} ModelData;

#endif
