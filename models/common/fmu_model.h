/* Interface between the shared FMI co-simulation layer and one model.
 *
 * A model folder supplies config.h (MODEL_IDENTIFIER, INSTANTIATION_TOKEN, the ValueReference
 * enum with N_VARIABLES last, the ModelData struct, MODEL_CAN_GET_SET_STATE, MODEL_HAS_STRINGS)
 * and model.c implementing the hooks declared below plus the variable table. Everything about
 * the FMI state machine, argument checks, logging and FMU state lives in fmu_core.c; the thin
 * fmi2_api.c and fmi3_api.c map it onto FMI 2.0 and FMI 3.0 (one of them per build).
 *
 * Status values: the hooks return the FMI 2.0 status enum (fmi2OK .. fmi2Pending), whose
 * values FMI 3.0's fmi3Status shares (OK 0, Warning 1, Discard 2, Error 3, Fatal 4).
 */
#ifndef FMU_MODEL_H
#define FMU_MODEL_H

#include <stdbool.h>
#include <stddef.h>

#include "fmi2Functions.h"
#include "config.h"

#ifndef MODEL_CAN_GET_SET_STATE
#define MODEL_CAN_GET_SET_STATE 0
#endif
#ifndef MODEL_HAS_STRINGS
#define MODEL_HAS_STRINGS 0
#endif

/* Relative tolerance on doStep's currentCommunicationPoint against the FMU's own time. */
#define COMMUNICATION_POINT_RTOL 1e-9

typedef enum {
    StartAndEnd = 1 << 0,
    Instantiated = 1 << 1,
    InitializationMode = 1 << 2,
    StepComplete = 1 << 3,
    StepFailed = 1 << 4,
    Terminated = 1 << 5,
    ErrorState = 1 << 6,
    Fatal = 1 << 7
} ModelState;

typedef enum { TypeReal, TypeInteger, TypeBoolean, TypeString } VariableType;
typedef enum { CausalityParameter, CausalityInput, CausalityOutput, CausalityLocal } Causality;
typedef enum { VariabilityFixed, VariabilityTunable, VariabilityContinuous, VariabilityDiscrete } Variability;

typedef struct {
    fmi2ValueReference vr;
    const char *name;
    VariableType type;
    Causality causality;
    Variability variability;
} ModelVariable;

/* A declared range of a Real variable; the table model_bounds[] is generated at build time
 * from the min/max attributes of modelDescription.xml (model_bounds.h). */
typedef struct {
    fmi2ValueReference vr;
    double min;
    double max;
} VariableBounds;

/* The variable table, indexed by value reference (model_variables[vr].vr == vr). */
extern const ModelVariable model_variables[N_VARIABLES];

struct ModelInstance;
/* Delivers one formatted log message to the importer (set by the FMI 2 or FMI 3 API). */
typedef void (*LogEmitter)(struct ModelInstance *comp, fmi2Status status, const char *category,
                           const char *message);

typedef struct ModelInstance {
    char *instanceName;
    char *resourcePath;        /* the FMU's resources folder, ending in '/' ("" if unknown) */
    LogEmitter emit;
    void *importerLogger;      /* the FMI version's logger callback, called by emit */
    void *importerEnvironment; /* fmi2ComponentEnvironment / fmi3InstanceEnvironment */
    fmi2CallbackAllocateMemory allocateMemory;
    fmi2CallbackFreeMemory freeMemory;
    fmi2Boolean loggingOn;
    ModelState state;
    double time;      /* s, current communication point */
    double stopTime;  /* s */
    bool stopTimeDefined;
    ModelData data;
} ModelInstance;

/* Resolve a file name against the FMU's resources folder unless it is absolute; writes at
 * most size bytes into out and returns false (logged) when the result does not fit. */
bool resolve_resource(ModelInstance *comp, const char *name, char *out, size_t size);

/* Logging through the environment's logger callback; errors are always logged. */
void log_error(ModelInstance *comp, const char *format, ...);
void log_warning(ModelInstance *comp, const char *format, ...);
void log_debug(ModelInstance *comp, const char *format, ...);

/* ---- hooks every model implements ---- */
/* Start values of every variable (at fmi2Instantiate and fmi2Reset). */
void model_set_start_values(ModelInstance *comp);
/* Check parameters, load resources, set the initial state (fmi2ExitInitializationMode). */
fmi2Status model_exit_initialization(ModelInstance *comp);
/* Get/set one Real by value reference; type and causality checks are already done. */
fmi2Status model_get_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real *value);
fmi2Status model_set_real(ModelInstance *comp, fmi2ValueReference vr, fmi2Real value);
#if MODEL_HAS_STRINGS
fmi2Status model_get_string(ModelInstance *comp, fmi2ValueReference vr, fmi2String *value);
fmi2Status model_set_string(ModelInstance *comp, fmi2ValueReference vr, fmi2String value);
#endif
/* Advance from t to t + h (inputs held constant); comp->time is updated by the caller. */
fmi2Status model_do_step(ModelInstance *comp, double t, double h);
/* Release what model_exit_initialization acquired (fmi2Reset, fmi2FreeInstance). */
void model_free_resources(ModelInstance *comp);

#endif
