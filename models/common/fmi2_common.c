/* The shared FMI 2.0 co-simulation layer: state machine, argument checks, logging, get/set
 * dispatch by value reference, FMU state and its serialisation, and doStep's check of the
 * communication point. Models supply only the hooks of fmu_model.h. Written for this project
 * after the structure of modelica/Reference-FMUs (no code copied).
 */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "fmu_model.h"

#define ALL_STATES (StartAndEnd | Instantiated | InitializationMode | StepComplete | StepFailed | \
                    Terminated | ErrorState | Fatal)
#define GET_STATES (InitializationMode | StepComplete | StepFailed | Terminated | ErrorState)
#define SET_STATES (Instantiated | InitializationMode | StepComplete)
#define STATE_STATES (Instantiated | InitializationMode | StepComplete | StepFailed | Terminated | \
                      ErrorState)

/* ---------------------------------------------------------------- logging */

static void log_message(ModelInstance *comp, fmi2Status status, const char *category,
                        const char *format, va_list args) {
    char buffer[1024];
    if (!comp || !comp->logger) return;
    vsnprintf(buffer, sizeof buffer, format, args);
    comp->logger(comp->componentEnvironment, comp->instanceName, status, category, "%s", buffer);
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

/* Returns false (and logs) when comp is NULL or the call is illegal in its current state. */
static bool allowed(ModelInstance *comp, const char *function, int states) {
    if (!comp) return false;
    if (!(comp->state & states)) {
        log_error(comp, "%s: illegal call in state %s", function, state_name(comp->state));
        return false;
    }
    return true;
}

static bool null_argument(ModelInstance *comp, const char *function, const char *arg,
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

/* ---------------------------------------------------------------- common functions */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    ModelInstance *comp = (ModelInstance *)c;
    static const char *known[] = {"logStatusWarning", "logStatusError", "logAll"};
    if (!allowed(comp, "fmi2SetDebugLogging", ALL_STATES & ~(StartAndEnd | Fatal)))
        return fmi2Error;
    if (nCategories > 0 && null_argument(comp, "fmi2SetDebugLogging", "categories", categories))
        return fmi2Error;
    for (size_t i = 0; i < nCategories; i++) {
        bool found = false;
        for (size_t k = 0; k < sizeof known / sizeof known[0]; k++)
            if (categories[i] && strcmp(categories[i], known[k]) == 0) found = true;
        if (!found) {
            log_error(comp, "fmi2SetDebugLogging: unknown log category \"%s\"",
                      categories[i] ? categories[i] : "(null)");
            return fmi2Error;
        }
    }
    comp->loggingOn = loggingOn;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    ModelInstance *comp;
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    if (!instanceName || !instanceName[0]) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, "?", fmi2Error, "logStatusError",
                              "fmi2Instantiate: missing instance name");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError",
                              "fmi2Instantiate: " MODEL_IDENTIFIER_STRING
                              " supports co-simulation only");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, INSTANTIATION_TOKEN) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError",
                              "fmi2Instantiate: GUID \"%s\" does not match " INSTANTIATION_TOKEN,
                              fmuGUID ? fmuGUID : "(null)");
        return NULL;
    }
    comp = (ModelInstance *)functions->allocateMemory(1, sizeof(ModelInstance));
    if (!comp) return NULL;
    comp->instanceName = (char *)functions->allocateMemory(strlen(instanceName) + 1, 1);
    if (!comp->instanceName) {
        functions->freeMemory(comp);
        return NULL;
    }
    strcpy(comp->instanceName, instanceName);
    comp->logger = functions->logger;
    comp->allocateMemory = functions->allocateMemory;
    comp->freeMemory = functions->freeMemory;
    comp->componentEnvironment = functions->componentEnvironment;
    comp->loggingOn = loggingOn;
    comp->time = 0.0;
    comp->stopTime = 0.0;
    comp->stopTimeDefined = false;
    model_set_start_values(comp);
    comp->state = Instantiated;
    log_debug(comp, "fmi2Instantiate: %s instantiated", MODEL_IDENTIFIER_STRING);
    return comp;
}

void fmi2FreeInstance(fmi2Component c) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!comp) return;
    model_free_resources(comp);
    comp->freeMemory(comp->instanceName);
    comp->freeMemory(comp);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    ModelInstance *comp = (ModelInstance *)c;
    (void)toleranceDefined;
    (void)tolerance;
    if (!allowed(comp, "fmi2SetupExperiment", Instantiated)) return fmi2Error;
    if (!isfinite(startTime) || (stopTimeDefined && !(stopTime >= startTime))) {
        log_error(comp, "fmi2SetupExperiment: invalid startTime %g / stopTime %g", startTime,
                  stopTime);
        return fmi2Error;
    }
    comp->time = startTime;
    comp->stopTimeDefined = stopTimeDefined ? true : false;
    comp->stopTime = stopTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2EnterInitializationMode", Instantiated)) return fmi2Error;
    comp->state = InitializationMode;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    ModelInstance *comp = (ModelInstance *)c;
    fmi2Status status;
    if (!allowed(comp, "fmi2ExitInitializationMode", InitializationMode)) return fmi2Error;
    status = model_exit_initialization(comp);
    comp->state = status <= fmi2Warning ? StepComplete : ErrorState;
    return status;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2Terminate", StepComplete | StepFailed | ErrorState)) return fmi2Error;
    comp->state = Terminated;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2Reset", ALL_STATES & ~(StartAndEnd | Fatal))) return fmi2Error;
    model_free_resources(comp);
    comp->time = 0.0;
    comp->stopTime = 0.0;
    comp->stopTimeDefined = false;
    model_set_start_values(comp);
    comp->state = Instantiated;
    return fmi2OK;
}

/* ---------------------------------------------------------------- get / set */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    fmi2Status status = fmi2OK;
    if (!allowed(comp, "fmi2GetReal", GET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (null_argument(comp, "fmi2GetReal", "vr[]", vr) ||
        null_argument(comp, "fmi2GetReal", "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Status s;
        if (!lookup(comp, "fmi2GetReal", vr[i], TypeReal)) return fmi2Error;
        s = model_get_real(comp, vr[i], &value[i]);
        if (s > status) status = s;
        if (status > fmi2Warning) return status;
    }
    return status;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2SetReal", SET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (null_argument(comp, "fmi2SetReal", "vr[]", vr) ||
        null_argument(comp, "fmi2SetReal", "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        const ModelVariable *var = lookup(comp, "fmi2SetReal", vr[i], TypeReal);
        if (!var || !settable(comp, "fmi2SetReal", var)) return fmi2Error;
        if (!isfinite(value[i])) {
            log_error(comp, "fmi2SetReal: %s (value reference %u) = %g is not finite", var->name,
                      (unsigned)vr[i], value[i]);
            return fmi2Error;
        }
        if (model_set_real(comp, vr[i], value[i]) > fmi2Warning) return fmi2Error;
    }
    return fmi2OK;
}

/* No model has Integer or Boolean variables: any value reference is an error. */
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    (void)value;
    if (!allowed(comp, "fmi2GetInteger", GET_STATES)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        if (!lookup(comp, "fmi2GetInteger", vr[i], TypeInteger)) return fmi2Error;
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    (void)value;
    if (!allowed(comp, "fmi2SetInteger", SET_STATES)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        if (!lookup(comp, "fmi2SetInteger", vr[i], TypeInteger)) return fmi2Error;
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    (void)value;
    if (!allowed(comp, "fmi2GetBoolean", GET_STATES)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        if (!lookup(comp, "fmi2GetBoolean", vr[i], TypeBoolean)) return fmi2Error;
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    (void)value;
    if (!allowed(comp, "fmi2SetBoolean", SET_STATES)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        if (!lookup(comp, "fmi2SetBoolean", vr[i], TypeBoolean)) return fmi2Error;
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2GetString", GET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (null_argument(comp, "fmi2GetString", "vr[]", vr) ||
        null_argument(comp, "fmi2GetString", "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        if (!lookup(comp, "fmi2GetString", vr[i], TypeString)) return fmi2Error;
#if MODEL_HAS_STRINGS
        if (model_get_string(comp, vr[i], &value[i]) > fmi2Warning) return fmi2Error;
#endif
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2SetString", SET_STATES)) return fmi2Error;
    if (nvr == 0) return fmi2OK;
    if (null_argument(comp, "fmi2SetString", "vr[]", vr) ||
        null_argument(comp, "fmi2SetString", "value[]", value))
        return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        const ModelVariable *var = lookup(comp, "fmi2SetString", vr[i], TypeString);
        if (!var || !settable(comp, "fmi2SetString", var)) return fmi2Error;
        if (null_argument(comp, "fmi2SetString", var->name, value[i])) return fmi2Error;
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

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    ModelInstance *comp = (ModelInstance *)c;
    SavedState *s;
    if (!allowed(comp, "fmi2GetFMUstate", STATE_STATES)) return fmi2Error;
    if (!state_supported(comp, "fmi2GetFMUstate")) return fmi2Error;
    if (null_argument(comp, "fmi2GetFMUstate", "FMUstate", FMUstate)) return fmi2Error;
    s = (SavedState *)*FMUstate;
    if (!s) {
        s = (SavedState *)comp->allocateMemory(1, sizeof(SavedState));
        if (!s) {
            log_error(comp, "fmi2GetFMUstate: out of memory");
            return fmi2Error;
        }
        *FMUstate = s;
    } else if (!saved_state_valid(comp, "fmi2GetFMUstate", s)) {
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

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    ModelInstance *comp = (ModelInstance *)c;
    const SavedState *s = (const SavedState *)FMUstate;
    if (!allowed(comp, "fmi2SetFMUstate", STATE_STATES)) return fmi2Error;
    if (!state_supported(comp, "fmi2SetFMUstate")) return fmi2Error;
    if (null_argument(comp, "fmi2SetFMUstate", "FMUstate", FMUstate)) return fmi2Error;
    if (!saved_state_valid(comp, "fmi2SetFMUstate", s)) return fmi2Error;
    comp->state = s->state;
    comp->time = s->time;
    comp->stopTime = s->stopTime;
    comp->stopTimeDefined = s->stopTimeDefined;
    comp->data = s->data;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!comp) return fmi2Error;
    if (!state_supported(comp, "fmi2FreeFMUstate")) return fmi2Error;
    if (null_argument(comp, "fmi2FreeFMUstate", "FMUstate", FMUstate)) return fmi2Error;
    if (*FMUstate) comp->freeMemory(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!comp || !state_supported(comp, "fmi2SerializedFMUstateSize")) return fmi2Error;
    if (null_argument(comp, "fmi2SerializedFMUstateSize", "FMUstate", FMUstate) ||
        null_argument(comp, "fmi2SerializedFMUstateSize", "size", size))
        return fmi2Error;
    *size = sizeof(SavedState);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!comp || !state_supported(comp, "fmi2SerializeFMUstate")) return fmi2Error;
    if (null_argument(comp, "fmi2SerializeFMUstate", "FMUstate", FMUstate) ||
        null_argument(comp, "fmi2SerializeFMUstate", "serializedState", serializedState))
        return fmi2Error;
    if (!saved_state_valid(comp, "fmi2SerializeFMUstate", (const SavedState *)FMUstate))
        return fmi2Error;
    if (size < sizeof(SavedState)) {
        log_error(comp, "fmi2SerializeFMUstate: buffer of %zu bytes, %zu needed", size,
                  sizeof(SavedState));
        return fmi2Error;
    }
    memcpy(serializedState, FMUstate, sizeof(SavedState));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate *FMUstate) {
    ModelInstance *comp = (ModelInstance *)c;
    SavedState s;
    if (!comp || !state_supported(comp, "fmi2DeSerializeFMUstate")) return fmi2Error;
    if (null_argument(comp, "fmi2DeSerializeFMUstate", "serializedState", serializedState) ||
        null_argument(comp, "fmi2DeSerializeFMUstate", "FMUstate", FMUstate))
        return fmi2Error;
    if (size != sizeof(SavedState)) {
        log_error(comp, "fmi2DeSerializeFMUstate: %zu bytes given, %zu expected", size,
                  sizeof(SavedState));
        return fmi2Error;
    }
    memcpy(&s, serializedState, sizeof s);
    if (!saved_state_valid(comp, "fmi2DeSerializeFMUstate", &s)) return fmi2Error;
    if (!*FMUstate) {
        *FMUstate = comp->allocateMemory(1, sizeof(SavedState));
        if (!*FMUstate) {
            log_error(comp, "fmi2DeSerializeFMUstate: out of memory");
            return fmi2Error;
        }
    }
    memcpy(*FMUstate, &s, sizeof s);
    return fmi2OK;
}

/* ---------------------------------------------------------------- unsupported capabilities */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown,
        (void)dvUnknown;
    log_error((ModelInstance *)c, "fmi2GetDirectionalDerivative is not supported");
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    log_error((ModelInstance *)c, "fmi2SetRealInputDerivatives is not supported");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    log_error((ModelInstance *)c, "fmi2GetRealOutputDerivatives is not supported");
    return fmi2Error;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    log_error((ModelInstance *)c, "fmi2CancelStep: doStep is synchronous, nothing to cancel");
    return fmi2Error;
}

/* ---------------------------------------------------------------- stepping */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    ModelInstance *comp = (ModelInstance *)c;
    double tolerance;
    fmi2Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(comp, "fmi2DoStep", StepComplete)) return fmi2Error;
    tolerance = COMMUNICATION_POINT_RTOL * fmax(1.0, fabs(comp->time));
    if (!(fabs(currentCommunicationPoint - comp->time) <= tolerance)) {
        log_error(comp,
                  "fmi2DoStep: currentCommunicationPoint %.17g does not match the FMU's time "
                  "%.17g (tolerance %g)",
                  currentCommunicationPoint, comp->time, tolerance);
        return fmi2Error;
    }
    if (!(communicationStepSize > 0.0) || !isfinite(communicationStepSize)) {
        log_error(comp, "fmi2DoStep: communicationStepSize %g must be positive",
                  communicationStepSize);
        return fmi2Error;
    }
    if (comp->stopTimeDefined &&
        comp->time + communicationStepSize > comp->stopTime + tolerance) {
        log_error(comp, "fmi2DoStep: step to %.17g passes the stop time %.17g",
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

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s, (void)value;
    log_error((ModelInstance *)c, "fmi2GetStatus: doStep is synchronous, no pending status");
    return fmi2Error;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2GetRealStatus", GET_STATES)) return fmi2Error;
    if (s != fmi2LastSuccessfulTime || !value) {
        log_error(comp, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is available");
        return fmi2Error;
    }
    *value = comp->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s, (void)value;
    log_error((ModelInstance *)c, "fmi2GetIntegerStatus: no integer status is defined");
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    ModelInstance *comp = (ModelInstance *)c;
    if (!allowed(comp, "fmi2GetBooleanStatus", GET_STATES)) return fmi2Error;
    if (s != fmi2Terminated || !value) {
        log_error(comp, "fmi2GetBooleanStatus: only fmi2Terminated is available");
        return fmi2Error;
    }
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s, (void)value;
    log_error((ModelInstance *)c, "fmi2GetStringStatus: no string status is defined");
    return fmi2Error;
}
