/* Identity of the KVLCC2 plant FMU: a third-party 320 m VLCC tanker at actuator level (rudder
 * order in degrees, shaft speed order in rpm) with an optional force interface (MN, MN m), its
 * own names and units (latitude/longitude on a sphere, compass degrees, knots, deg/s, kN, kW). */
#ifndef CONFIG_H
#define CONFIG_H

#define MODEL_IDENTIFIER KVLCC2
#define MODEL_IDENTIFIER_STRING "KVLCC2"
#define INSTANTIATION_TOKEN "{9b3f2c61-5d8e-4a07-b1c4-7e6a0d2f9e35}"
#define MODEL_CAN_GET_SET_STATE 1
#define MODEL_HAS_STRINGS 0

typedef enum {
    /* inputs */
    vr_RudderOrder, vr_ShaftSpeedOrder, vr_SurgeForceDemand, vr_YawMomentDemand,
    vr_CurrentSpeed, vr_CurrentDirection, vr_WindSpeed, vr_WindDirection, vr_WaveHeight,
    /* outputs */
    vr_Latitude, vr_Longitude, vr_Heading, vr_SurgeSpeed, vr_SwaySpeed, vr_YawRate,
    vr_SpeedOverGround, vr_CourseOverGround, vr_RudderAngle, vr_ShaftSpeed, vr_PropellerThrust,
    vr_ShaftPower,
    /* parameters */
    vr_ForceMode, vr_InitialLatitude, vr_InitialLongitude, vr_InitialHeading, vr_InitialSpeed,
    vr_InitialShaftSpeed, vr_MaxSurgeForce, vr_MaxYawMoment, vr_IntegrationStep,
    N_VARIABLES
} ValueReference;

/* state: latitude, longitude (rad), heading (rad), surge, sway (m/s), yaw rate (rad/s),
 * rudder angle (rad), shaft speed (1/s), governor set point (1/s), governor integral (N m) */
enum { S_LAT, S_LON, S_PSI, S_U, S_V, S_R, S_DELTA, S_N, S_NREF, S_GOV, S_NSTATES };

typedef struct {
    /* inputs, as the FMU's users give them (deg, rpm, MN, MN m, m/s, deg, m/s, deg, m) */
    double rudder_order_deg, shaft_order_rpm, surge_demand_MN, yaw_demand_MNm;
    double current_mps, current_towards_deg, wind_mps, wind_from_deg, hs_m;
    /* parameters */
    double force_mode, start_lat_deg, start_lon_deg, start_heading_deg, start_speed_kn;
    double start_shaft_rpm, max_surge_MN, max_yaw_MNm, h_int_s;
    double X[S_NSTATES];
} ModelData;

#endif
