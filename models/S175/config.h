/* Identity of the S175 plant FMU: a third-party 175 m container ship with its own names and
 * units (latitude/longitude, km, compass degrees, knots, degrees per minute, kN, kN m, rpm):
 * force inputs by default, rudder and shaft speed orders with actuator_mode = 1. */
#ifndef CONFIG_H
#define CONFIG_H

#define MODEL_IDENTIFIER S175
#define MODEL_IDENTIFIER_STRING "S175"
#define INSTANTIATION_TOKEN "{7d2a5e18-93c4-4b6f-8e01-5fa4c2d9b176}"
#define MODEL_CAN_GET_SET_STATE 1
#define MODEL_HAS_STRINGS 0

typedef enum {
    /* inputs */
    vr_propeller_thrust, vr_rudder_moment, vr_current_set, vr_current_drift, vr_wind_speed_true,
    vr_wind_from, vr_wave_height,
    /* outputs */
    vr_lat, vr_lon, vr_north_km, vr_east_km, vr_heading, vr_stw, vr_sway_speed, vr_rot, vr_sog,
    vr_cog,
    /* parameters */
    vr_start_lat, vr_start_lon, vr_start_heading, vr_start_stw, vr_max_thrust,
    vr_max_rudder_moment, vr_internal_step,
    /* the actuator interface, appended so that the force interface keeps its value references */
    vr_rudder_order, vr_shaft_speed_order, vr_rudder_position, vr_shaft_speed, vr_shaft_thrust,
    vr_actuator_mode, vr_start_shaft_speed,
    N_VARIABLES
} ValueReference;

/* state: latitude, longitude (rad), north, east from the start (m), heading (rad),
 * surge, sway (m/s), yaw rate (rad/s), rudder angle (rad), shaft speed (1/s) */
enum { S_LAT, S_LON, S_NORTH, S_EAST, S_PSI, S_U, S_V, S_R, S_DELTA, S_N, S_NSTATES };

typedef struct {
    /* inputs, as the FMU's users give them (kN, kN m, deg, kn, m) */
    double thrust_kN, moment_kNm, set_deg, drift_kn, wind_kn, wind_from_deg, hs_m;
    /* parameters */
    double start_lat_deg, start_lon_deg, start_heading_deg, start_stw_kn;
    double max_thrust_kN, max_moment_kNm, h_int_s;
    /* actuator interface: orders (deg, rpm), mode (0 forces, 1 actuators), initial shaft speed (rpm) */
    double rudder_order_deg, shaft_order_rpm, actuator_mode, start_shaft_rpm;
    double X[S_NSTATES];
} ModelData;

#endif
