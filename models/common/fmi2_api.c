/* FMI 2.0 co-simulation functions, each a thin mapping onto the shared core (fmu_core.c). */
#include <stdlib.h>
#include <string.h>

#include "fmu_core.h"

#define COMP ((ModelInstance *)c)

static void emit_fmi2(ModelInstance *comp, fmi2Status status, const char *category,
                      const char *message) {
    fmi2CallbackLogger logger = (fmi2CallbackLogger)comp->importerLogger;
    if (logger)
        logger((fmi2ComponentEnvironment)comp->importerEnvironment, comp->instanceName, status,
               category, "%s", message);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    return core_set_debug_logging(COMP, "fmi2SetDebugLogging", loggingOn ? true : false,
                                  nCategories, categories);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
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
    {
        ModelInstance *comp = core_instantiate(
            instanceName, NULL, emit_fmi2, (void *)functions->logger,
            functions->componentEnvironment, functions->allocateMemory, functions->freeMemory,
            loggingOn ? true : false);
        core_set_resource_uri(comp, fmuResourceLocation);
        return comp;
    }
}

void fmi2FreeInstance(fmi2Component c) { core_free_instance(COMP); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    return core_setup_experiment(COMP, "fmi2SetupExperiment", Instantiated, startTime,
                                 stopTimeDefined ? true : false, stopTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return core_enter_initialization(COMP, "fmi2EnterInitializationMode");
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    return core_exit_initialization(COMP, "fmi2ExitInitializationMode");
}

fmi2Status fmi2Terminate(fmi2Component c) { return core_terminate(COMP, "fmi2Terminate"); }

fmi2Status fmi2Reset(fmi2Component c) { return core_reset(COMP, "fmi2Reset"); }

/* ---------------------------------------------------------------- get / set */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    return core_get_reals(COMP, "fmi2GetReal", vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    return core_set_reals(COMP, "fmi2SetReal", vr, nvr, value);
}

/* No model has Integer or Boolean variables: any value reference is an error. */
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    (void)value;
    return core_check_references(COMP, "fmi2GetInteger", GET_STATES, vr, nvr, TypeInteger);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    (void)value;
    return core_check_references(COMP, "fmi2SetInteger", SET_STATES, vr, nvr, TypeInteger);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    (void)value;
    return core_check_references(COMP, "fmi2GetBoolean", GET_STATES, vr, nvr, TypeBoolean);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    (void)value;
    return core_check_references(COMP, "fmi2SetBoolean", SET_STATES, vr, nvr, TypeBoolean);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    return core_get_strings(COMP, "fmi2GetString", vr, nvr, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    return core_set_strings(COMP, "fmi2SetString", vr, nvr, value);
}

/* ---------------------------------------------------------------- FMU state */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    return core_get_state(COMP, "fmi2GetFMUstate", FMUstate);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    return core_set_state(COMP, "fmi2SetFMUstate", FMUstate);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    return core_free_state(COMP, "fmi2FreeFMUstate", FMUstate);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    return core_state_size(COMP, "fmi2SerializedFMUstateSize", FMUstate, size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size) {
    return core_serialize_state(COMP, "fmi2SerializeFMUstate", FMUstate,
                                (unsigned char *)serializedState, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate *FMUstate) {
    return core_deserialize_state(COMP, "fmi2DeSerializeFMUstate",
                                  (const unsigned char *)serializedState, size, FMUstate);
}

/* ---------------------------------------------------------------- unsupported capabilities */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown,
        (void)dvUnknown;
    return core_unsupported(COMP, "fmi2GetDirectionalDerivative is not supported");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return core_unsupported(COMP, "fmi2SetRealInputDerivatives is not supported");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return core_unsupported(COMP, "fmi2GetRealOutputDerivatives is not supported");
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return core_unsupported(COMP, "fmi2CancelStep: doStep is synchronous, nothing to cancel");
}

/* ---------------------------------------------------------------- stepping */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    return core_do_step(COMP, "fmi2DoStep", currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s, (void)value;
    return core_unsupported(COMP, "fmi2GetStatus: doStep is synchronous, no pending status");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (!core_allowed(COMP, "fmi2GetRealStatus", GET_STATES)) return fmi2Error;
    if (s != fmi2LastSuccessfulTime || !value)
        return core_unsupported(COMP, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is available");
    *value = COMP->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s, (void)value;
    return core_unsupported(COMP, "fmi2GetIntegerStatus: no integer status is defined");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    if (!core_allowed(COMP, "fmi2GetBooleanStatus", GET_STATES)) return fmi2Error;
    if (s != fmi2Terminated || !value)
        return core_unsupported(COMP, "fmi2GetBooleanStatus: only fmi2Terminated is available");
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s, (void)value;
    return core_unsupported(COMP, "fmi2GetStringStatus: no string status is defined");
}
