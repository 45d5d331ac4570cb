/* FMI 3.0 co-simulation functions, each a thin mapping onto the shared core (fmu_core.c).
 *
 * The models are the FMI 2.0 ones: Float64 (FMI 2 Real) and String variables, scalar only,
 * co-simulation without event mode, intermediate updates or early return. The independent
 * variable `time` has the value reference FMI3_TIME_VR, outside the model's table.
 */
#include <stdlib.h>
#include <string.h>

#include "fmu_core.h"
#include "fmi3Functions.h"

#define FMI3_TIME_VR 1000000u
#define INST ((ModelInstance *)instance)

static void emit_fmi3(ModelInstance *comp, fmi2Status status, const char *category,
                      const char *message) {
    fmi3LogMessageCallback logger = (fmi3LogMessageCallback)comp->importerLogger;
    if (logger)
        logger((fmi3InstanceEnvironment)comp->importerEnvironment, (fmi3Status)status, category,
               message);
}

/* Scalar variables only: one value per value reference. */
static bool scalar_counts(ModelInstance *comp, const char *function, size_t nvr, size_t nValues) {
    if (nvr == nValues) return true;
    log_error(comp, "%s: %zu values for %zu value references (all variables are scalars)",
              function, nValues, nvr);
    return false;
}

/* For the FMI 3 types no model has: any value reference is unknown. */
static fmi3Status no_variables(ModelInstance *comp, const char *function, int states,
                               const fmi3ValueReference vr[], size_t nvr) {
    if (!core_allowed(comp, function, states)) return fmi3Error;
    if (nvr == 0) return fmi3OK;
    log_error(comp, "%s: unknown value reference %u (this FMU has no variables of that type)",
              function, vr ? (unsigned)vr[0] : 0u);
    return fmi3Error;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    return (fmi3Status)core_set_debug_logging(INST, "fmi3SetDebugLogging", loggingOn, nCategories,
                                              categories);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateModelExchange: " MODEL_IDENTIFIER_STRING
                   " supports co-simulation only");
    (void)instanceName;
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)visible, (void)earlyReturnAllowed, (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (!instanceName || !instanceName[0]) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateCoSimulation: missing instance name");
        return NULL;
    }
    if (!instantiationToken || strcmp(instantiationToken, INSTANTIATION_TOKEN) != 0) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateCoSimulation: instantiationToken does not match "
                       INSTANTIATION_TOKEN);
        return NULL;
    }
    if (eventModeUsed || nRequiredIntermediateVariables > 0) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateCoSimulation: " MODEL_IDENTIFIER_STRING
                       " has no event mode and no intermediate variables");
        return NULL;
    }
    return core_instantiate(instanceName, resourcePath, emit_fmi3, (void *)logMessage,
                            instanceEnvironment, calloc, free, loggingOn);
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: " MODEL_IDENTIFIER_STRING
                   " supports co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { core_free_instance(INST); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)toleranceDefined, (void)tolerance;
    if (core_setup_experiment(INST, "fmi3EnterInitializationMode", Instantiated, startTime,
                              stopTimeDefined, stopTime) != fmi2OK)
        return fmi3Error;
    return (fmi3Status)core_enter_initialization(INST, "fmi3EnterInitializationMode");
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    return (fmi3Status)core_exit_initialization(INST, "fmi3ExitInitializationMode");
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    return (fmi3Status)core_unsupported(INST, "fmi3EnterEventMode: no event mode");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    return (fmi3Status)core_terminate(INST, "fmi3Terminate");
}

fmi3Status fmi3Reset(fmi3Instance instance) { return (fmi3Status)core_reset(INST, "fmi3Reset"); }

/* ---------------------------------------------------------------- get / set */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    const char *fn = "fmi3GetFloat64";
    fmi3Status status = fmi3OK;
    if (!scalar_counts(INST, fn, nvr, nValues)) return fmi3Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi3Status s;
        if (vr && values && vr[i] == FMI3_TIME_VR) {
            if (!core_allowed(INST, fn, GET_STATES)) return fmi3Error;
            values[i] = INST->time;
            continue;
        }
        s = (fmi3Status)core_get_reals(INST, fn, vr ? &vr[i] : NULL, 1, values ? &values[i] : NULL);
        if (s > status) status = s;
        if (status > fmi3Warning) return status;
    }
    return nvr == 0 ? (fmi3Status)core_get_reals(INST, fn, vr, 0, values) : status;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    if (!scalar_counts(INST, "fmi3SetFloat64", nvr, nValues)) return fmi3Error;
    return (fmi3Status)core_set_reals(INST, "fmi3SetFloat64", vr, nvr, values);
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         fmi3String values[], size_t nValues) {
    if (!scalar_counts(INST, "fmi3GetString", nvr, nValues)) return fmi3Error;
    return (fmi3Status)core_get_strings(INST, "fmi3GetString", vr, nvr, values);
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3String values[], size_t nValues) {
    if (!scalar_counts(INST, "fmi3SetString", nvr, nValues)) return fmi3Error;
    return (fmi3Status)core_set_strings(INST, "fmi3SetString", vr, nvr, values);
}

#define NO_GET(Name, Type)                                                                        \
    fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,    \
                             Type values[], size_t nValues) {                                     \
        (void)values, (void)nValues;                                                              \
        return no_variables(INST, "fmi3Get" #Name, GET_STATES, vr, nvr);                          \
    }
#define NO_SET(Name, Type)                                                                        \
    fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,    \
                             const Type values[], size_t nValues) {                               \
        (void)values, (void)nValues;                                                              \
        return no_variables(INST, "fmi3Set" #Name, SET_STATES, vr, nvr);                          \
    }
#define NO_GET_SET(Name, Type) NO_GET(Name, Type) NO_SET(Name, Type)

NO_GET_SET(Float32, fmi3Float32)
NO_GET_SET(Int8, fmi3Int8)
NO_GET_SET(UInt8, fmi3UInt8)
NO_GET_SET(Int16, fmi3Int16)
NO_GET_SET(UInt16, fmi3UInt16)
NO_GET_SET(Int32, fmi3Int32)
NO_GET_SET(UInt32, fmi3UInt32)
NO_GET_SET(Int64, fmi3Int64)
NO_GET_SET(UInt64, fmi3UInt64)
NO_GET_SET(Boolean, fmi3Boolean)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueSizes, (void)values, (void)nValues;
    return no_variables(INST, "fmi3GetBinary", GET_STATES, vr, nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueSizes, (void)values, (void)nValues;
    return no_variables(INST, "fmi3SetBinary", SET_STATES, vr, nvr);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[]) {
    (void)values;
    return no_variables(INST, "fmi3GetClock", GET_STATES, vr, nvr);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    (void)values;
    return no_variables(INST, "fmi3SetClock", SET_STATES, vr, nvr);
}

/* ---------------------------------------------------------------- dependencies */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *nDependencies) {
    (void)vr, (void)nDependencies;
    return (fmi3Status)core_unsupported(INST, "fmi3GetNumberOfVariableDependencies is not supported");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    return (fmi3Status)core_unsupported(INST, "fmi3GetVariableDependencies is not supported");
}

/* ---------------------------------------------------------------- FMU state */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return (fmi3Status)core_get_state(INST, "fmi3GetFMUState", FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    return (fmi3Status)core_set_state(INST, "fmi3SetFMUState", FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return (fmi3Status)core_free_state(INST, "fmi3FreeFMUState", FMUState);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    return (fmi3Status)core_state_size(INST, "fmi3SerializedFMUStateSize", FMUState, size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size) {
    return (fmi3Status)core_serialize_state(INST, "fmi3SerializeFMUState", FMUState,
                                            serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState) {
    return (fmi3Status)core_deserialize_state(INST, "fmi3DeserializeFMUState", serializedState,
                                              size, FMUState);
}

/* ---------------------------------------------------------------- unsupported capabilities */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    return (fmi3Status)core_unsupported(INST, "fmi3GetDirectionalDerivative is not supported");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    return (fmi3Status)core_unsupported(INST, "fmi3GetAdjointDerivative is not supported");
}

#define UNSUPPORTED(Name)                                                                         \
    fmi3Status fmi3##Name(fmi3Instance instance) {                                                \
        return (fmi3Status)core_unsupported(INST, "fmi3" #Name " is not supported");              \
    }

UNSUPPORTED(EnterConfigurationMode)
UNSUPPORTED(ExitConfigurationMode)
UNSUPPORTED(EvaluateDiscreteStates)
UNSUPPORTED(EnterContinuousTimeMode)
UNSUPPORTED(EnterStepMode)

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    (void)vr, (void)nvr, (void)intervals, (void)qualifiers;
    return (fmi3Status)core_unsupported(INST, "fmi3GetIntervalDecimal: no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions, (void)qualifiers;
    return (fmi3Status)core_unsupported(INST, "fmi3GetIntervalFraction: no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[]) {
    (void)vr, (void)nvr, (void)shifts;
    return (fmi3Status)core_unsupported(INST, "fmi3GetShiftDecimal: no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return (fmi3Status)core_unsupported(INST, "fmi3GetShiftFraction: no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[]) {
    (void)vr, (void)nvr, (void)intervals;
    return (fmi3Status)core_unsupported(INST, "fmi3SetIntervalDecimal: no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return (fmi3Status)core_unsupported(INST, "fmi3SetIntervalFraction: no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[]) {
    (void)vr, (void)nvr, (void)shifts;
    return (fmi3Status)core_unsupported(INST, "fmi3SetShiftDecimal: no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return (fmi3Status)core_unsupported(INST, "fmi3SetShiftFraction: no clocks");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    (void)discreteStatesNeedUpdate, (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged, (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined, (void)nextEventTime;
    return (fmi3Status)core_unsupported(INST, "fmi3UpdateDiscreteStates: no event mode");
}

/* Model-exchange functions: this FMU is co-simulation only. */
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    return (fmi3Status)core_unsupported(INST, "fmi3CompletedIntegratorStep: co-simulation only");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    return (fmi3Status)core_unsupported(INST, "fmi3SetTime: co-simulation only");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 states[], size_t n) {
    (void)states, (void)n;
    return (fmi3Status)core_unsupported(INST, "fmi3SetContinuousStates: co-simulation only");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t n) {
    (void)derivatives, (void)n;
    return (fmi3Status)core_unsupported(INST, "fmi3GetContinuousStateDerivatives: co-simulation only");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 indicators[], size_t n) {
    (void)indicators, (void)n;
    return (fmi3Status)core_unsupported(INST, "fmi3GetEventIndicators: co-simulation only");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 states[], size_t n) {
    (void)states, (void)n;
    return (fmi3Status)core_unsupported(INST, "fmi3GetContinuousStates: co-simulation only");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t n) {
    (void)nominals, (void)n;
    return (fmi3Status)core_unsupported(INST, "fmi3GetNominalsOfContinuousStates: co-simulation only");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    (void)n;
    return (fmi3Status)core_unsupported(INST, "fmi3GetNumberOfEventIndicators: co-simulation only");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    (void)n;
    return (fmi3Status)core_unsupported(INST, "fmi3GetNumberOfContinuousStates: co-simulation only");
}

/* ---------------------------------------------------------------- stepping */

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues;
    return (fmi3Status)core_unsupported(INST, "fmi3GetOutputDerivatives is not supported");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    fmi3Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (core_null_argument(INST, "fmi3DoStep", "eventHandlingNeeded", eventHandlingNeeded) ||
        core_null_argument(INST, "fmi3DoStep", "terminateSimulation", terminateSimulation) ||
        core_null_argument(INST, "fmi3DoStep", "earlyReturn", earlyReturn) ||
        core_null_argument(INST, "fmi3DoStep", "lastSuccessfulTime", lastSuccessfulTime))
        return fmi3Error;
    status = (fmi3Status)core_do_step(INST, "fmi3DoStep", currentCommunicationPoint,
                                      communicationStepSize);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = INST ? INST->time : currentCommunicationPoint;
    return status;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    return (fmi3Status)core_unsupported(INST, "fmi3ActivateModelPartition: co-simulation only");
}
