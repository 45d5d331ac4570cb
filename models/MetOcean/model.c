/* MetOcean environment FMU: wind, significant wave height and current at the point (x, y) and
 * the FMU's time, bilinear in space and linear in time in a MOGRID2 (or static MOGRID1) grid
 * file. Format, equations and conventions: readme.md. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmu_model.h"

#define GRID_MAGIC_STATIC "MOGRID1\n"  /* no time axis */
#define GRID_MAGIC_TIMED "MOGRID2\n"   /* with nt and the times */
#define MAGIC_BYTES 8
#define OUTSIDE_TOLERANCE 1e-9 /* in grid cells */
#define MAX_NODES 100000
#define MAX_TIMES 1000000

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
    if (g->values) comp->freeMemory(g->values);
    if (g->times) comp->freeMemory(g->times);
    comp->freeMemory(g);
    comp->data.grid = NULL;
}

/* Reads n little-endian float64 into out; false when the file ends first. */
static int read_doubles(FILE *f, double *out, size_t n) {
    unsigned char cell[8];
    for (size_t k = 0; k < n; k++) {
        if (fread(cell, 1, 8, f) != 8) return 0;
        out[k] = read_float64_le(cell);
    }
    return 1;
}

/* Reads and checks the header after the magic: nx, ny, (nt), x0, dx, y0, dy. */
static int read_header(FILE *f, MetOceanGrid *g, int timed) {
    unsigned char b[12 + 32];
    const size_t counts = timed ? 12 : 8;
    if (fread(b, 1, counts + 32, f) != counts + 32) return 0;
    g->nx = read_int32_le(b);
    g->ny = read_int32_le(b + 4);
    g->nt = timed ? read_int32_le(b + 8) : 1;
    g->x0 = read_float64_le(b + counts);
    g->dx = read_float64_le(b + counts + 8);
    g->y0 = read_float64_le(b + counts + 16);
    g->dy = read_float64_le(b + counts + 24);
    return 1;
}

/* Reads comp->data.grid_file (a relative name is taken in the FMU's resources folder); logs
 * the file name and the reason on failure. */
static fmi2Status load_grid(ModelInstance *comp) {
    char path[GRID_FILE_MAX + 4096];
    unsigned char magic[MAGIC_BYTES], extra;
    MetOceanGrid *g;
    size_t count;
    FILE *f;
    int timed;

    if (!comp->data.grid_file[0]) {
        log_error(comp, "grid_file (value reference %u) is not set", (unsigned)vr_grid_file);
        return fmi2Error;
    }
    if (!resolve_resource(comp, comp->data.grid_file, path, sizeof path)) return fmi2Error;
    f = fopen(path, "rb");
    if (!f) {
        log_error(comp, "grid_file \"%s\" cannot be opened (missing or unreadable)", path);
        return fmi2Error;
    }
    if (fread(magic, 1, MAGIC_BYTES, f) != MAGIC_BYTES) timed = -1;
    else if (memcmp(magic, GRID_MAGIC_TIMED, MAGIC_BYTES) == 0) timed = 1;
    else if (memcmp(magic, GRID_MAGIC_STATIC, MAGIC_BYTES) == 0) timed = 0;
    else timed = -1;
    g = (MetOceanGrid *)comp->allocateMemory(1, sizeof *g);
    if (!g) {
        fclose(f);
        log_error(comp, "grid_file \"%s\": out of memory", path);
        return fmi2Error;
    }
    g->times = g->values = NULL;
    comp->data.grid = g; /* free_grid releases whatever is allocated when a check fails */
    if (timed < 0 || !read_header(f, g, timed)) {
        log_error(comp, "grid_file \"%s\" is not a MOGRID1 or MOGRID2 file (bad magic or short header)",
                  path);
        goto fail;
    }
    if (g->nx < 2 || g->ny < 2 || g->nx > MAX_NODES || g->ny > MAX_NODES || g->nt < 1 ||
        g->nt > MAX_TIMES || !(g->dx > 0.0) || !(g->dy > 0.0) || !isfinite(g->x0) ||
        !isfinite(g->y0) || !isfinite(g->dx) || !isfinite(g->dy)) {
        log_error(comp, "grid_file \"%s\": invalid header nx=%d ny=%d nt=%d dx=%g dy=%g", path, g->nx,
                  g->ny, g->nt, g->dx, g->dy);
        goto fail;
    }
    g->times = (double *)comp->allocateMemory((size_t)g->nt, sizeof(double));
    count = (size_t)g->nt * N_FIELDS * (size_t)g->nx * (size_t)g->ny;
    g->values = (double *)comp->allocateMemory(count, sizeof(double));
    if (!g->times || !g->values) {
        log_error(comp, "grid_file \"%s\": out of memory for %zu values", path, count);
        goto fail;
    }
    if (!timed) g->times[0] = 0.0;
    else if (!read_doubles(f, g->times, (size_t)g->nt)) {
        log_error(comp, "grid_file \"%s\" is truncated in its %d times", path, g->nt);
        goto fail;
    }
    for (int k = 0; k < g->nt; k++) {
        if (!isfinite(g->times[k]) || (k > 0 && !(g->times[k] > g->times[k - 1]))) {
            log_error(comp, "grid_file \"%s\": time %d (%g s) is not finite or not after the one before",
                      path, k, g->times[k]);
            goto fail;
        }
    }
    for (size_t k = 0; k < count; k++) {
        if (!read_doubles(f, g->values + k, 1)) {
            log_error(comp, "grid_file \"%s\" is truncated: %zu of %zu values", path, k, count);
            goto fail;
        }
        if (!isfinite(g->values[k])) {
            log_error(comp, "grid_file \"%s\": value %zu is not finite", path, k);
            goto fail;
        }
    }
    if (fread(&extra, 1, 1, f) != 0) {
        log_error(comp, "grid_file \"%s\" has trailing bytes after %zu values", path, count);
        goto fail;
    }
    fclose(f);
    log_debug(comp, "grid_file \"%s\": %d x %d nodes, x %g..%g m, y %g..%g m, %d times %g..%g s", path,
              g->nx, g->ny, g->x0, g->x0 + (g->nx - 1) * g->dx, g->y0, g->y0 + (g->ny - 1) * g->dy,
              g->nt, g->times[0], g->times[g->nt - 1]);
    return fmi2OK;
fail:
    fclose(f);
    free_grid(comp);
    return fmi2Error;
}

/* ---------------------------------------------------------------- interpolation */

/* Time step k and weight w with value = (1 - w) F[k] + w F[k + 1] at time t: t is held at
 * the first and the last time; exactly at a time step w = 0 (w = 1 at the last one). */
static void time_weight(const MetOceanGrid *g, double t, int *k, double *w) {
    int lo = 0, hi = g->nt - 1;
    const double held = fmin(fmax(t, g->times[0]), g->times[g->nt - 1]);
    if (g->nt == 1) {
        *k = 0;
        *w = 0.0;
        return;
    }
    while (hi - lo > 1) { /* times[lo] <= held < times[hi], or held at the last time */
        const int mid = lo + (hi - lo) / 2;
        if (g->times[mid] <= held) lo = mid;
        else hi = mid;
    }
    *k = lo;
    *w = (held - g->times[lo]) / (g->times[lo + 1] - g->times[lo]);
}

/* Bilinear in space at each of the two time steps around t, linear between them, into data.fields. */
static fmi2Status evaluate(ModelInstance *comp, double t, const char *function) {
    ModelData *d = &comp->data;
    const MetOceanGrid *g;
    double fi, fj, tx, ty, w;
    int i, j, k;

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
    time_weight(g, t, &k, &w);
    for (int f = 0; f < N_FIELDS; f++) {
        double at[2] = {0.0, 0.0};
        for (int s = 0; s < (g->nt > 1 ? 2 : 1); s++) {
            const double *v = g->values + ((size_t)(k + s) * N_FIELDS + f) * g->nx * g->ny;
            const double v00 = v[(size_t)i * g->ny + j], v01 = v[(size_t)i * g->ny + j + 1];
            const double v10 = v[(size_t)(i + 1) * g->ny + j], v11 = v[(size_t)(i + 1) * g->ny + j + 1];
            at[s] = (1 - tx) * ((1 - ty) * v00 + ty * v01) + tx * ((1 - ty) * v10 + ty * v11);
        }
        d->fields[f] = g->nt > 1 ? (1 - w) * at[0] + w * at[1] : at[0];
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- hooks */

void model_set_start_values(ModelInstance *comp) {
    ModelData *d = &comp->data;
    d->x = d->y = 0.0;
    for (int f = 0; f < N_FIELDS; f++) d->fields[f] = 0.0;
    strcpy(d->grid_file, DEFAULT_GRID_FILE); /* shipped in the FMU's resources */
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
    /* outputs are direct feedthrough: recompute from the current inputs at the FMU's time */
    if (evaluate(comp, comp->time, "reading an output") != fmi2OK) return fmi2Error;
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
        log_error(comp, "grid_file (value reference %u) is longer than %d bytes",
                  (unsigned)vr, GRID_FILE_MAX - 1);
        return fmi2Error;
    }
    strcpy(comp->data.grid_file, value);
    free_grid(comp);
    return fmi2OK;
}

fmi2Status model_do_step(ModelInstance *comp, double t, double h) {
    return evaluate(comp, t + h, "step"); /* the outputs at the end of the step */
}

void model_free_resources(ModelInstance *comp) { free_grid(comp); }
