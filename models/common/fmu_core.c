/* The version-neutral core of the shared FMI co-simulation layer: state machine, argument
 * checks, logging, get/set dispatch by value reference, FMU state and its serialisation, and
 * the step's check of the communication point. fmi2_api.c and fmi3_api.c are thin mappings
 * of the FMI 2.0 and FMI 3.0 functions onto it; models supply only the hooks of fmu_model.h.
 * Written for this project after the structure of modelica/Reference-FMUs (no code copied).
 */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmu_core.h"
#include "model_bounds.h" /* generated at build time from modelDescription.xml min/max */

/* ---------------------------------------------------------------- logging */

static void log_message(ModelInstance *comp, fmi2Status status, const char *category,
                        const char *format, va_list args) {
    char buffer[1024];
    if (!comp || !comp->emit) return;
    vsnprintf(buffer, sizeof buffer, format, args);
    comp->emit(comp, status, category, buffer);
}

void log_error(ModelInstance *comp, const char *format, ...) {
    va_list args;
    va_start(args, format);
    log_message(comp, fmi2Error, "logStatusError", format, args);
    va_end(args);
}

void log_warning(ModelInstance *comp, const char *format, ...) {
    va_list args;
    if (!comp || !comp->loggingOn) return;
    va_start(args, format);
    log_message(comp, fmi2Warning, "logStatusWarning", format, args);
    va_end(args);
}

void log_debug(ModelInstance *comp, const char *format, ...) {
    va_list args;
    if (!comp || !comp->loggingOn) return;
    va_start(args, format);
    log_message(comp, fmi2OK, "logAll", format, args);
    va_end(args);
}

/* ---------------------------------------------------------------- checks */

static const char *state_name(ModelState s) {
    switch (s) {
    case StartAndEnd: return "StartAndEnd";
    case Instantiated: return "Instantiated";
    case InitializationMode: return "InitializationMode";
    case StepComplete: return "StepComplete";
    case StepFailed: return "StepFailed";
    case Terminated: return "Terminated";
    case ErrorState: return "Error";
    case Fatal: return "Fatal";
    }
    return "unknown";
}

bool core_allowed(ModelInstance *comp, const char *function, int states) {
    if (!comp) return false;
    if (!(comp->state & states)) {
        log_error(comp, "%s: illegal call in state %s", function, state_name(comp->state));
        return false;
    }
    return true;
}

bool core_null_argument(ModelInstance *comp, const char *function, const char *arg,
                        const void *p) {
    if (p) return false;
    log_error(comp, "%s: invalid argument %s = NULL", function, arg);
    return true;
}

/* Checks a value reference against the variable table and the expected type. */
static const ModelVariable *lookup(ModelInstance *comp, const char *function,
                                   fmi2ValueReference vr, VariableType type) {
    static const char *type_names[] = {"Real", "Integer", "Boolean", "String"};
    if (vr >= N_VARIABLES || model_variables[vr].vr != vr) {
        log_error(comp, "%s: unknown value reference %u", function, (unsigned)vr);
        return NULL;
    }
    if (model_variables[vr].type != type) {
        log_error(comp, "%s: variable %s (value reference %u) is not of type %s", function,
                  model_variables[vr].name, (unsigned)vr, type_names[type]);
        return NULL;
    }
    return &model_variables[vr];
}

/* May this variable be set in the current state? */
static bool settable(ModelInstance *comp, const char *function, const ModelVariable *var) {
    if (var->causality == CausalityInput) return true;
    if (var->causality == CausalityParameter) {
        if (comp->state & (Instantiated | InitializationMode)) return true;
        if (var->variability == VariabilityTunable) return true;
        log_error(comp, "%s: fixed parameter %s (value reference %u) cannot be set in state %s",
                  function, var->name, (unsigned)var->vr, state_name(comp->state));
        return false;
    }
    log_error(comp, "%s: variable %s (value reference %u) is an output or local and cannot be set",
              function, var->name, (unsigned)var->vr);
    return false;
}

/* The declared range [min, max] of a Real variable (modelDescription.xml), if it has one. */
static bool within_bounds(ModelInstance *comp, const char *function, const ModelVariable *var,
                          double value) {
    for (size_t k = 0; k < sizeof model_bounds / sizeof model_bounds[0]; k++) {
        const VariableBounds *b = &model_bounds[k];
        if (b->vr != var->vr) continue;
        if (value < b->min || value > b->max) {
            log_error(comp, "%s: %s (value reference %u) = %g is outside its range [%g, %g]",
                      function, var->name, (unsigned)var->vr, value, b->min, b->max);
            return false;
        }
    }
    return true;
}

/* ---------------------------------------------------------------- life cycle */

fmi2Status core_set_debug_logging(ModelInstance *comp, const char *function, bool loggingOn,
                                  size_t nCategories, const char *const categories[]) {
    static const char *known[] = {"logStatusWarning", "logStatusError", "logAll"};
    if (!core_allowed(comp, function, ALL_STATES & ~(StartAndEnd | Fatal))) return fmi2Error;
    if (nCategories > 0 && core_null_argument(comp, function, "categories", categories))
        return fmi2Error;
    for (size_t i = 0; i < nCategories; i++) {
        bool found = false;
        for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
            if (categories[i] && strcmp(categories[i], known[k]) == 0) found = true;
        if (!found) {
            log_error(comp, "%s: unknown log category \"%s\"", function,
                      categories[i] ? categories[i] : "(null)");
            return fmi2Error;
        }
    }
    comp->loggingOn = loggingOn;
    return fmi2OK;
}

static char *copy_string(fmi2CallbackAllocateMemory allocate, const char *text) {
    char *copy = (char *)allocate(strlen(text) + 1, 1);
    if (copy) strcpy(copy, text);
    return copy;
}

/* A resources folder path with a trailing '/', or "" for none. */
static char *folder_path(fmi2CallbackAllocateMemory allocate, const char *path) {
    size_t n = path ? strlen(path) : 0;
    char *copy = (char *)allocate(n + 2, 1);
    if (!copy) return NULL;
    if (n) {
        memcpy(copy, path, n);
        if (copy[n - 1] != '/') copy[n++] = '/';
    }
    copy[n] = '\0';
    return copy;
}

ModelInstance *core_instantiate(const char *instanceName, const char *resourcePath, LogEmitter emit,
                                void *logger, void *environment,
                                fmi2CallbackAllocateMemory allocate, fmi2CallbackFreeMemory release,
                                bool loggingOn) {
    ModelInstance *comp = (ModelInstance *)allocate(1, sizeof(ModelInstance));
    if (!comp) return NULL;
    comp->instanceName = copy_string(allocate, instanceName);
    comp->resourcePath = folder_path(allocate, resourcePath);
    if (!comp->instanceName || !comp->resourcePath) {
        if (comp->instanceName) release(comp->instanceName);
        if (comp->resourcePath) release(comp->resourcePath);
        release(comp);
        return NULL;
    }
    comp->emit = emit;
    comp->importerLogger = logger;
    comp->importerEnvironment = environment;
    comp->allocateMemory = allocate;
    comp->freeMemory = release;
    comp->loggingOn = loggingOn;
    comp->time = 0.0;
    comp->stopTime = 0.0;
    comp->stopTimeDefined = false;
    model_set_start_values(comp);
    comp->state = Instantiated;
    log_debug(comp, "%s instantiated", MODEL_IDENTIFIER_STRING);
    return comp;
}

void core_free_instance(ModelInstance *comp) {
    if (!comp) return;
    model_free_resources(comp);
    comp->freeMemory(comp->instanceName);
    comp->freeMemory(comp->resourcePath);
    comp->freeMemory(comp);
}

static int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

void core_set_resource_uri(ModelInstance *comp, const char *uri) {
    char *path;
    size_t k = 0;
    if (!comp || !uri) return;
    if (strncmp(uri, "file:///", 8) == 0) uri += 7;        /* file:///p -> /p */
    else if (strncmp(uri, "file://localhost/", 17) == 0) uri += 16;
    else if (strncmp(uri, "file:/", 6) == 0) uri += 5;     /* file:/p -> /p */
    else return;                                          /* not a local file: no resources */
    path = (char *)comp->allocateMemory(strlen(uri) + 1, 1);
    if (!path) return;
    for (size_t i = 0; uri[i]; i++) {                     /* percent-decoding */
        if (uri[i] == '%' && hex_value(uri[i + 1]) >= 0 && hex_value(uri[i + 2]) >= 0) {
            path[k++] = (char)(hex_value(uri[i + 1]) * 16 + hex_value(uri[i + 2]));
            i += 2;
        } else {
            path[k++] = uri[i];
        }
    }
    path[k] = '\0';
    comp->freeMemory(comp->resourcePath);
    comp->resourcePath = folder_path(comp->allocateMemory, path);
    comp->freeMemory(path);
    if (!comp->resourcePath) comp->resourcePath = copy_string(comp->allocateMemory, "");
}

bool resolve_resource(ModelInstance *comp, const char *name, char *out, size_t size) {
    int n;
    if (name[0] == '/' || !comp->resourcePath || !comp->resourcePath[0])
        n = snprintf(out, size, "%s", name);
    else
        n = snprintf(out, size, "%s%s", comp->resourcePath, name);
    if (n < 0 || (size_t)n >= size) {
        log_error(comp, "the path of \"%s\" is longer than %zu bytes", name, size - 1);
        return false;
    }
    return true;
}

fmi2Status core_setup_experiment(ModelInstance *comp, const char *function, int states,
                                 double startTime, bool stopTimeDefined, double stopTime) {
    if (!core_allowed(comp, function, states)) return fmi2Error;
    if (!isfinite(startTime) || (stopTimeDefined && !(stopTime >= startTime))) {
        log_error(comp, "%s: invalid startTime %g / stopTime %g", function, startTime, stopTime);
        return fmi2Error;
    }
    comp->time = startTime;
    comp->stopTimeDefined = stopTimeDefined;
    comp->stopTime = stopTime;
    return fmi2OK;
}

fmi2Status core_enter_initialization(ModelInstance *comp, const char *function) {
    if (!core_allowed(comp, function, Instantiated)) return fmi2Error;
    comp->state = InitializationMode;
    return fmi2OK;
}

fmi2Status core_exit_initialization(ModelInstance *comp, const char *function) {
    fmi2Status status;
    if (!core_allowed(comp, function, InitializationMode)) return fmi2Error;
    status = model_exit_initialization(comp);
    comp->state = status <= fmi2Warning ? StepComplete : ErrorState;
    return status;
}

fmi2Status core_terminate(ModelInstance *comp, const char *function) {
    if (!core_allowed(comp, function, StepComplete | StepFailed | ErrorState)) return fmi2Error;
    comp->state = Terminated;
    return fmi2OK;
}

fmi2Status core_reset(ModelInstance *comp, const char *function) {
    if (!core_allowed(comp, function, ALL_STATES & ~(StartAndEnd | Fatal))) return fmi2Error;
    model_free_resources(comp);
    comp->time = 0.0;
    comp->stopTime = 0.0;
    comp->stopTimeDefined = false;
    model_set_start_values(comp);
    comp->state = Instantiated;
    return fmi2OK;
}

/* ---------------------------------------------------------------- get / set */

fmi2Status core_get_reals(ModelInstance *comp, const char *function, const fmi2ValueReference vr[],
                          size_t nvr, double value[]) {
    fmi2Status status = fmi2OK;
    if (!core_allowed(comp, function, GET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (core_null_argument(comp, function, "vr[]", vr) ||
        core_null_argument(comp, function, "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Status s;
        if (!lookup(comp, function, vr[i], TypeReal)) return fmi2Error;
        s = model_get_real(comp, vr[i], &value[i]);
        if (s > status) status = s;
        if (status > fmi2Warning) return status;
    }
    return status;
}

fmi2Status core_set_reals(ModelInstance *comp, const char *function, const fmi2ValueReference vr[],
                          size_t nvr, const double value[]) {
    if (!core_allowed(comp, function, SET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (core_null_argument(comp, function, "vr[]", vr) ||
        core_null_argument(comp, function, "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        const ModelVariable *var = lookup(comp, function, vr[i], TypeReal);
        if (!var || !settable(comp, function, var)) return fmi2Error;
        if (!isfinite(value[i])) {
            log_error(comp, "%s: %s (value reference %u) = %g is not finite", function, var->name,
                      (unsigned)vr[i], value[i]);
            return fmi2Error;
        }
        if (!within_bounds(comp, function, var, value[i])) return fmi2Error;
        if (model_set_real(comp, vr[i], value[i]) > fmi2Warning) return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status core_check_references(ModelInstance *comp, const char *function, int states,
                                 const fmi2ValueReference vr[], size_t nvr, VariableType type) {
    if (!core_allowed(comp, function, states)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        if (!lookup(comp, function, vr[i], type)) return fmi2Error;
    return fmi2OK;
}

fmi2Status core_get_strings(ModelInstance *comp, const char *function,
                            const fmi2ValueReference vr[], size_t nvr, const char *value[]) {
    if (!core_allowed(comp, function, GET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (core_null_argument(comp, function, "vr[]", vr) ||
        core_null_argument(comp, function, "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        if (!lookup(comp, function, vr[i], TypeString)) return fmi2Error;
#if MODEL_HAS_STRINGS
        if (model_get_string(comp, vr[i], &value[i]) > fmi2Warning) return fmi2Error;
#endif
    }
    return fmi2OK;
}

fmi2Status core_set_strings(ModelInstance *comp, const char *function,
                            const fmi2ValueReference vr[], size_t nvr, const char *const value[]) {
    if (!core_allowed(comp, function, SET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (core_null_argument(comp, function, "vr[]", vr) ||
        core_null_argument(comp, function, "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        const ModelVariable *var = lookup(comp, function, vr[i], TypeString);
        if (!var || !settable(comp, function, var)) return fmi2Error;
        if (core_null_argument(comp, function, var->name, value[i])) return fmi2Error;
#if MODEL_HAS_STRINGS
        if (model_set_string(comp, vr[i], value[i]) > fmi2Warning) return fmi2Error;
#endif
    }
    return fmi2OK;
}

/* ---------------------------------------------------------------- FMU state */

#define STATE_MAGIC 0x464d5553u /* "FMUS" */

typedef struct {
    uint32_t magic;
    uint32_t size; /* sizeof(SavedState): guards against a state from another build */
    ModelState state;
    double time;
    double stopTime;
    bool stopTimeDefined;
    ModelData data;
} SavedState;

static bool state_supported(ModelInstance *comp, const char *function) {
#if MODEL_CAN_GET_SET_STATE
    (void)comp;
    (void)function;
    return true;
#else
    log_error(comp, "%s: " MODEL_IDENTIFIER_STRING " cannot get and set its FMU state", function);
    return false;
#endif
}

static bool saved_state_valid(ModelInstance *comp, const char *function, const SavedState *s) {
    if (s->magic != STATE_MAGIC || s->size != sizeof(SavedState)) {
        log_error(comp, "%s: the FMU state does not belong to this FMU", function);
        return false;
    }
    return true;
}

fmi2Status core_get_state(ModelInstance *comp, const char *function, void **state) {
    SavedState *s;
    if (!core_allowed(comp, function, STATE_STATES)) return fmi2Error;
    if (!state_supported(comp, function)) return fmi2Error;
    if (core_null_argument(comp, function, "FMUstate", state)) return fmi2Error;
    s = (SavedState *)*state;
    if (!s) {
        s = (SavedState *)comp->allocateMemory(1, sizeof(SavedState));
        if (!s) {
            log_error(comp, "%s: out of memory", function);
            return fmi2Error;
        }
        *state = s;
    } else if (!saved_state_valid(comp, function, s)) {
        return fmi2Error;
    }
    s->magic = STATE_MAGIC;
    s->size = sizeof(SavedState);
    s->state = comp->state;
    s->time = comp->time;
    s->stopTime = comp->stopTime;
    s->stopTimeDefined = comp->stopTimeDefined;
    s->data = comp->data;
    return fmi2OK;
}

fmi2Status core_set_state(ModelInstance *comp, const char *function, const void *state) {
    const SavedState *s = (const SavedState *)state;
    if (!core_allowed(comp, function, STATE_STATES)) return fmi2Error;
    if (!state_supported(comp, function)) return fmi2Error;
    if (core_null_argument(comp, function, "FMUstate", state)) return fmi2Error;
    if (!saved_state_valid(comp, function, s)) return fmi2Error;
    comp->state = s->state;
    comp->time = s->time;
    comp->stopTime = s->stopTime;
    comp->stopTimeDefined = s->stopTimeDefined;
    comp->data = s->data;
    return fmi2OK;
}

fmi2Status core_free_state(ModelInstance *comp, const char *function, void **state) {
    if (!comp) return fmi2Error;
    if (!state_supported(comp, function)) return fmi2Error;
    if (core_null_argument(comp, function, "FMUstate", state)) return fmi2Error;
    if (*state) comp->freeMemory(*state);
    *state = NULL;
    return fmi2OK;
}

fmi2Status core_state_size(ModelInstance *comp, const char *function, const void *state,
                           size_t *size) {
    if (!comp || !state_supported(comp, function)) return fmi2Error;
    if (core_null_argument(comp, function, "FMUstate", state) ||
        core_null_argument(comp, function, "size", size))
        return fmi2Error;
    *size = sizeof(SavedState);
    return fmi2OK;
}

fmi2Status core_serialize_state(ModelInstance *comp, const char *function, const void *state,
                                unsigned char buffer[], size_t size) {
    if (!comp || !state_supported(comp, function)) return fmi2Error;
    if (core_null_argument(comp, function, "FMUstate", state) ||
        core_null_argument(comp, function, "serializedState", buffer))
        return fmi2Error;
    if (!saved_state_valid(comp, function, (const SavedState *)state)) return fmi2Error;
    if (size < sizeof(SavedState)) {
        log_error(comp, "%s: buffer of %zu bytes, %zu needed", function, size, sizeof(SavedState));
        return fmi2Error;
    }
    memcpy(buffer, state, sizeof(SavedState));
    return fmi2OK;
}

fmi2Status core_deserialize_state(ModelInstance *comp, const char *function,
                                  const unsigned char buffer[], size_t size, void **state) {
    SavedState s;
    if (!comp || !state_supported(comp, function)) return fmi2Error;
    if (core_null_argument(comp, function, "serializedState", buffer) ||
        core_null_argument(comp, function, "FMUstate", state))
        return fmi2Error;
    if (size != sizeof(SavedState)) {
        log_error(comp, "%s: %zu bytes given, %zu expected", function, size, sizeof(SavedState));
        return fmi2Error;
    }
    memcpy(&s, buffer, sizeof s);
    if (!saved_state_valid(comp, function, &s)) return fmi2Error;
    if (!*state) {
        *state = comp->allocateMemory(1, sizeof(SavedState));
        if (!*state) {
            log_error(comp, "%s: out of memory", function);
            return fmi2Error;
        }
    }
    memcpy(*state, &s, sizeof s);
    return fmi2OK;
}

/* ---------------------------------------------------------------- stepping */

fmi2Status core_do_step(ModelInstance *comp, const char *function, double currentCommunicationPoint,
                        double communicationStepSize) {
    double tolerance;
    fmi2Status status;
    if (!core_allowed(comp, function, StepComplete)) return fmi2Error;
    tolerance = COMMUNICATION_POINT_RTOL * fmax(1.0, fabs(comp->time));
    if (!(fabs(currentCommunicationPoint - comp->time) <= tolerance)) {
        log_error(comp,
                  "%s: currentCommunicationPoint %.17g does not match the FMU's time "
                  "%.17g (tolerance %g)",
                  function, currentCommunicationPoint, comp->time, tolerance);
        return fmi2Error;
    }
    if (!(communicationStepSize > 0.0) || !isfinite(communicationStepSize)) {
        log_error(comp, "%s: communicationStepSize %g must be positive", function,
                  communicationStepSize);
        return fmi2Error;
    }
    if (comp->stopTimeDefined &&
        comp->time + communicationStepSize > comp->stopTime + tolerance) {
        log_error(comp, "%s: step to %.17g passes the stop time %.17g", function,
                  comp->time + communicationStepSize, comp->stopTime);
        return fmi2Error;
    }
    status = model_do_step(comp, comp->time, communicationStepSize);
    if (status > fmi2Warning) {
        comp->state = ErrorState;
        return status;
    }
    comp->time += communicationStepSize;
    return status;
}

fmi2Status core_unsupported(ModelInstance *comp, const char *message) {
    log_error(comp, "%s", message);
    return fmi2Error;
}
