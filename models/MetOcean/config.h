/* Identity of the MetOcean environment FMU: identifier, token, value references, model data. */
#ifndef CONFIG_H
#define CONFIG_H

#define MODEL_IDENTIFIER MetOcean
#define MODEL_IDENTIFIER_STRING "MetOcean"
#define INSTANTIATION_TOKEN "{0c9e4f7a-2d61-4b8e-a3f5-7e1b9d2c6a38}"
#define MODEL_CAN_GET_SET_STATE 0 /* holds a loaded grid; the outputs depend on (x, y, time) only */
/* The grid shipped in the FMU's resources: the paper's default weather, so that the FMU's
 * default experiment runs without a file of the user's. */
#define DEFAULT_GRID_FILE "default.grid"
#define MODEL_HAS_STRINGS 1
#define GRID_FILE_MAX 4096

typedef enum {
    vr_x, vr_y,                                                  /* inputs, m */
    vr_wind_speed, vr_wind_direction, vr_wind_north, vr_wind_east, /* outputs */
    vr_hs, vr_current_north, vr_current_east,
    vr_grid_file,                                                /* string parameter */
    N_VARIABLES
} ValueReference;

enum { FIELD_WIND_NORTH, FIELD_WIND_EAST, FIELD_HS, FIELD_CURRENT_NORTH, FIELD_CURRENT_EAST,
       N_FIELDS };

typedef struct {
    int nx, ny;       /* nodes along x (north) and y (east) */
    int nt;           /* time steps (1: a static field) */
    double x0, dx;    /* m */
    double y0, dy;    /* m */
    double *times;    /* nt times, s on the simulation clock, strictly increasing */
    double *values;   /* nt * N_FIELDS blocks of nx*ny, index [k][f][i * ny + j] */
} MetOceanGrid;

typedef struct {
    double x, y;                      /* m, query point */
    double fields[N_FIELDS];          /* last evaluated values at (x, y) */
    char grid_file[GRID_FILE_MAX];    /* MOGRID1/MOGRID2 file: absolute, or in the resources */
    MetOceanGrid *grid;               /* loaded at fmi2ExitInitializationMode */
} ModelData;

#endif
