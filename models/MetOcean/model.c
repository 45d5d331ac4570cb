/* MetOcean environment FMU: wind, significant wave height and current at the point (x, y),
 * bilinear in a MOGRID1 grid file. Format, equations and conventions: readme.md. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmu_model.h"

#define GRID_MAGIC "MOGRID1\n"
#define GRID_HEADER_BYTES (8 + 2 * 4 + 4 * 8)
#define OUTSIDE_TOLERANCE 1e-9 /* in grid cells */

#define VAR(name, causality, variability) {vr_##name, #name, TypeReal, causality, variability}

const ModelVariable model_variables[N_VARIABLES] = {
    VAR(x, CausalityInput, VariabilityContinuous),
    VAR(y, CausalityInput, VariabilityContinuous),
    VAR(wind_speed, CausalityOutput, VariabilityContinuous),
    VAR(wind_direction, CausalityOutput, VariabilityContinuous),
    VAR(wind_north, CausalityOutput, VariabilityContinuous),
    VAR(wind_east, CausalityOutput, VariabilityContinuous),
    VAR(hs, CausalityOutput, VariabilityContinuous),
    VAR(current_north, CausalityOutput, VariabilityContinuous),
    VAR(current_east, CausalityOutput, VariabilityContinuous),
    {vr_grid_file, "grid_file", TypeString, CausalityParameter, VariabilityFixed},
};

/* ---------------------------------------------------------------- grid file */

static int32_t read_int32_le(const unsigned char *b) {
    return (int32_t)((uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 |
                     (uint32_t)b[3] << 24);
}

static double read_float64_le(const unsigned char *b) {
    uint64_t bits = 0;
    double value;
    for (int k = 7; k >= 0; k--) bits = bits << 8 | b[k];
    memcpy(&value, &bits, sizeof value);
    return value;
}

static void free_grid(ModelInstance *comp) {
    MetOceanGrid *g = comp->data.grid;
    if (!g) return;
    comp->freeMemory(g->values);
    comp->freeMemory(g);
    comp->data.grid = NULL;
}

/* Reads comp->data.grid_file; logs the file name and the reason on failure. */
static fmi2Status load_grid(ModelInstance *comp) {
    const char *path = comp->data.grid_file;
    unsigned char header[GRID_HEADER_BYTES], cell[8];
    MetOceanGrid *g;
    size_t count;
    FILE *f;

    if (!path[0]) {
        log_error(comp, "grid_file (value reference %u) is not set", (unsigned)vr_grid_file);
        return fmi2Error;
    }
    f = fopen(path, "rb");
    if (!f) {
        log_error(comp, "grid_file \"%s\" cannot be opened (missing or unreadable)", path);
        return fmi2Error;
    }
    if (fread(header, 1, sizeof header, f) != sizeof header ||
        memcmp(header, GRID_MAGIC, 8) != 0) {
        log_error(comp, "grid_file \"%s\" is not a MOGRID1 file (bad magic or short header)",
                  path);
        fclose(f);
        return fmi2Error;
    }
    g = (MetOceanGrid *)comp->allocateMemory(1, sizeof *g);
    if (!g) {
        fclose(f);
        log_error(comp, "grid_file \"%s\": out of memory", path);
        return fmi2Error;
    }
    g->nx = read_int32_le(header + 8);
    g->ny = read_int32_le(header + 12);
    g->x0 = read_float64_le(header + 16);
    g->dx = read_float64_le(header + 24);
    g->y0 = read_float64_le(header + 32);
    g->dy = read_float64_le(header + 40);
    if (g->nx < 2 || g->ny < 2 || g->nx > 100000 || g->ny > 100000 || !(g->dx > 0.0) ||
        !(g->dy > 0.0) || !isfinite(g->x0) || !isfinite(g->y0) || !isfinite(g->dx) ||
        !isfinite(g->dy)) {
        log_error(comp, "grid_file \"%s\": invalid header nx=%d ny=%d dx=%g dy=%g", path, g->nx,
                  g->ny, g->dx, g->dy);
        comp->freeMemory(g);
        fclose(f);
        return fmi2Error;
    }
    count = (size_t)N_FIELDS * (size_t)g->nx * (size_t)g->ny;
    g->values = (double *)comp->allocateMemory(count, sizeof(double));
    if (!g->values) {
        log_error(comp, "grid_file \"%s\": out of memory for %zu values", path, count);
        comp->freeMemory(g);
        fclose(f);
        return fmi2Error;
    }
    for (size_t k = 0; k < count; k++) {
        if (fread(cell, 1, 8, f) != 8) {
            log_error(comp, "grid_file \"%s\" is truncated: %zu of %zu values", path, k, count);
            comp->freeMemory(g->values);
            comp->freeMemory(g);
            fclose(f);
            return fmi2Error;
        }
        g->values[k] = read_float64_le(cell);
        if (!isfinite(g->values[k])) {
            log_error(comp, "grid_file \"%s\": value %zu is not finite", path, k);
            comp->freeMemory(g->values);
            comp->freeMemory(g);
            fclose(f);
            return fmi2Error;
        }
    }
    if (fread(cell, 1, 1, f) != 0) {
        log_error(comp, "grid_file \"%s\" has trailing bytes after %zu values", path, count);
        comp->freeMemory(g->values);
        comp->freeMemory(g);
        fclose(f);
        return fmi2Error;
    }
    fclose(f);
    comp->data.grid = g;
    log_debug(comp, "grid_file \"%s\": %d x %d nodes, x %g..%g m, y %g..%g m", path, g->nx, g->ny,
              g->x0, g->x0 + (g->nx - 1) * g->dx, g->y0, g->y0 + (g->ny - 1) * g->dy);
    return fmi2OK;
}

/* ---------------------------------------------------------------- interpolation */

/* Bilinear interpolation of every field at (x, y) into data.fields. */
static fmi2Status evaluate(ModelInstance *comp, const char *function) {
    ModelData *d = &comp->data;
    const MetOceanGrid *g;
    double fi, fj, tx, ty;
    int i, j;

    if (!d->grid && load_grid(comp) != fmi2OK) return fmi2Error;
    g = d->grid;
    fi = (d->x - g->x0) / g->dx;
    fj = (d->y - g->y0) / g->dy;
    if (!(fi >= -OUTSIDE_TOLERANCE && fi <= g->nx - 1 + OUTSIDE_TOLERANCE &&
          fj >= -OUTSIDE_TOLERANCE && fj <= g->ny - 1 + OUTSIDE_TOLERANCE)) {
        log_error(comp, "%s: point x = %.3f m, y = %.3f m is outside the grid "
                  "x %.3f..%.3f m, y %.3f..%.3f m of \"%s\"", function, d->x, d->y, g->x0,
                  g->x0 + (g->nx - 1) * g->dx, g->y0, g->y0 + (g->ny - 1) * g->dy, d->grid_file);
        return fmi2Error;
    }
    fi = fmin(fmax(fi, 0.0), g->nx - 1.0);
    fj = fmin(fmax(fj, 0.0), g->ny - 1.0);
    i = (int)fi < g->nx - 2 ? (int)fi : g->nx - 2;
    j = (int)fj < g->ny - 2 ? (int)fj : g->ny - 2;
    tx = fi - i;
    ty = fj - j;
    for (int f = 0; f < N_FIELDS; f++) {
        const double *v = g->values + (size_t)f * g->nx * g->ny;
        const double v00 = v[(size_t)i * g->ny + j], v01 = v[(size_t)i * g->ny + j + 1];
        const double v10 = v[(size_t)(i + 1) * g->ny + j], v11 = v[(size_t)(i + 1) * g->ny + j + 1];
        d->fields[f] = (1 - tx) * ((1 - ty) * v00 + ty * v01) + tx * ((1 - ty) * v10 + ty * v11);
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- hooks */

void model_set_start_values(ModelInstance *comp) {
    ModelData *d = &comp->data;
    d->x = d->y = 0.0;
    for (int f = 0; f < N_FIELDS; f++) d->fields[f] = 0.0;
    d->grid_file[0] = '\0';
    d->grid = NULL;
}

fmi2Status model_exit_initialization(ModelInstance *comp) {
    free_grid(comp); /* (re)read the file named now */
    return load_grid(comp);
}

fmi2Status model_get_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real *value) {
    ModelData *d = &comp->data;
    const double *w = d->fields;
    if (vr == vr_x) { *value = d->x; return fmi2OK; }
    if (vr == vr_y) { *value = d->y; return fmi2OK; }
    /* outputs are direct feedthrough: recompute from the current inputs */
    if (evaluate(comp, "fmi2GetReal") != fmi2OK) return fmi2Error;
    switch (vr) {
    case vr_wind_speed: *value = hypot(w[FIELD_WIND_NORTH], w[FIELD_WIND_EAST]); break;
    case vr_wind_direction:
        *value = atan2(-w[FIELD_WIND_EAST], -w[FIELD_WIND_NORTH]); /* from, clockwise from north */
        break;
    case vr_wind_north: *value = w[FIELD_WIND_NORTH]; break;
    case vr_wind_east: *value = w[FIELD_WIND_EAST]; break;
    case vr_hs: *value = w[FIELD_HS]; break;
    case vr_current_north: *value = w[FIELD_CURRENT_NORTH]; break;
    case vr_current_east: *value = w[FIELD_CURRENT_EAST]; break;
    default: return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status model_set_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real value) {
    if (vr == vr_x) comp->data.x = value;
    else if (vr == vr_y) comp->data.y = value;
    else return fmi2Error;
    return fmi2OK;
}

fmi2Status model_get_string(ModelInstance *comp, fmi2ValueReference vr, fmi2String *value) {
    (void)vr;
    *value = comp->data.grid_file;
    return fmi2OK;
}

fmi2Status model_set_string(ModelInstance *comp, fmi2ValueReference vr, fmi2String value) {
    if (strlen(value) >= GRID_FILE_MAX) {
        log_error(comp, "fmi2SetString: grid_file (value reference %u) is longer than %d bytes",
                  (unsigned)vr, GRID_FILE_MAX - 1);
        return fmi2Error;
    }
    strcpy(comp->data.grid_file, value);
    free_grid(comp);
    return fmi2OK;
}

fmi2Status model_do_step(ModelInstance *comp, double t, double h) {
    (void)t;
    (void)h;
    return evaluate(comp, "fmi2DoStep");
}

void model_free_resources(ModelInstance *comp) { free_grid(comp); }
