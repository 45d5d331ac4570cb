/* The version-neutral core of the shared FMI layer, called by fmi2_api.c and fmi3_api.c.
 *
 * Every function takes the name of the FMI function it serves (e.g. "fmi2GetReal" or
 * "fmi3GetFloat64") so that messages name what the importer called.
 */
#ifndef FMU_CORE_H
#define FMU_CORE_H

#include "fmu_model.h"

#define ALL_STATES (StartAndEnd | Instantiated | InitializationMode | StepComplete | StepFailed | \
                    Terminated | ErrorState | Fatal)
#define GET_STATES (InitializationMode | StepComplete | StepFailed | Terminated | ErrorState)
#define SET_STATES (Instantiated | InitializationMode | StepComplete)
#define STATE_STATES (Instantiated | InitializationMode | StepComplete | StepFailed | Terminated | \
                      ErrorState)

/* Returns false (and logs) when comp is NULL or the call is illegal in its current state. */
bool core_allowed(ModelInstance *comp, const char *function, int states);
/* Logs and returns true when p is NULL. */
bool core_null_argument(ModelInstance *comp, const char *function, const char *arg, const void *p);

/* Allocates an instance and sets the start values; NULL when out of memory. resourcePath is
 * the resources folder as a plain path (FMI 3.0) or NULL; set it from an FMI 2.0 URI with
 * core_set_resource_uri. */
ModelInstance *core_instantiate(const char *instanceName, const char *resourcePath, LogEmitter emit,
                                void *logger, void *environment,
                                fmi2CallbackAllocateMemory allocate, fmi2CallbackFreeMemory release,
                                bool loggingOn);
/* Store the resources folder given as a file URI (FMI 2.0's fmuResourceLocation). */
void core_set_resource_uri(ModelInstance *comp, const char *uri);
void core_free_instance(ModelInstance *comp);

fmi2Status core_set_debug_logging(ModelInstance *comp, const char *function, bool loggingOn,
                                  size_t nCategories, const char *const categories[]);
fmi2Status core_setup_experiment(ModelInstance *comp, const char *function, int states,
                                 double startTime, bool stopTimeDefined, double stopTime);
fmi2Status core_enter_initialization(ModelInstance *comp, const char *function);
fmi2Status core_exit_initialization(ModelInstance *comp, const char *function);
fmi2Status core_terminate(ModelInstance *comp, const char *function);
fmi2Status core_reset(ModelInstance *comp, const char *function);

fmi2Status core_get_reals(ModelInstance *comp, const char *function, const fmi2ValueReference vr[],
                          size_t nvr, double value[]);
fmi2Status core_set_reals(ModelInstance *comp, const char *function, const fmi2ValueReference vr[],
                          size_t nvr, const double value[]);
fmi2Status core_get_strings(ModelInstance *comp, const char *function,
                            const fmi2ValueReference vr[], size_t nvr, const char *value[]);
fmi2Status core_set_strings(ModelInstance *comp, const char *function,
                            const fmi2ValueReference vr[], size_t nvr, const char *const value[]);
/* For the types no model has: every value reference is an error unless it has that type. */
fmi2Status core_check_references(ModelInstance *comp, const char *function, int states,
                                 const fmi2ValueReference vr[], size_t nvr, VariableType type);

fmi2Status core_get_state(ModelInstance *comp, const char *function, void **state);
fmi2Status core_set_state(ModelInstance *comp, const char *function, const void *state);
fmi2Status core_free_state(ModelInstance *comp, const char *function, void **state);
fmi2Status core_state_size(ModelInstance *comp, const char *function, const void *state,
                           size_t *size);
fmi2Status core_serialize_state(ModelInstance *comp, const char *function, const void *state,
                                unsigned char buffer[], size_t size);
fmi2Status core_deserialize_state(ModelInstance *comp, const char *function,
                                  const unsigned char buffer[], size_t size, void **state);

/* Advances from the communication point to comp->time + step; checks both. */
fmi2Status core_do_step(ModelInstance *comp, const char *function, double currentCommunicationPoint,
                        double communicationStepSize);

/* Logs that a capability is not offered and returns fmi2Error. */
fmi2Status core_unsupported(ModelInstance *comp, const char *message);

#endif
