/* The FMI 3.0 functions lag3 does not offer (model exchange, scheduled execution, other types, clocks,
 * derivatives): an importer resolves every function of the standard, so each exists and answers fmi3Error (3).
 * Defined without the header's prototypes: none of them is ever called with meaning. */
#include <stddef.h>

const char *fmi3GetVersion(void) { return "3.0"; }
int fmi3SetDebugLogging(void) { return 0; }
void *fmi3InstantiateModelExchange(void) { return NULL; }
void *fmi3InstantiateScheduledExecution(void) { return NULL; }
int fmi3EnterEventMode(void) { return 3; }
int fmi3Reset(void) { return 3; }
#ifdef SILRIG_NO_STATE /* the FMUs of tests/fmu/int32_outputs.c keep no state an importer can save */
int fmi3GetFMUState(void) { return 3; }
int fmi3SetFMUState(void) { return 3; }
int fmi3FreeFMUState(void) { return 3; }
int fmi3SerializedFMUStateSize(void) { return 3; }
int fmi3SerializeFMUState(void) { return 3; }
int fmi3DeserializeFMUState(void) { return 3; }
#endif
int fmi3GetFloat32(void) { return 3; }
int fmi3GetInt8(void) { return 3; }
int fmi3GetUInt8(void) { return 3; }
int fmi3GetInt16(void) { return 3; }
int fmi3GetUInt16(void) { return 3; }
#ifndef SILRIG_OWN_GET_INT32 /* defined by tests/fmu/int32_outputs.c, whose FMUs read Int32 outputs */
int fmi3GetInt32(void) { return 3; }
#endif
int fmi3GetUInt32(void) { return 3; }
int fmi3GetInt64(void) { return 3; }
int fmi3GetUInt64(void) { return 3; }
int fmi3GetBoolean(void) { return 3; }
int fmi3GetString(void) { return 3; }
int fmi3GetBinary(void) { return 3; }
int fmi3GetClock(void) { return 3; }
int fmi3SetFloat32(void) { return 3; }
int fmi3SetInt8(void) { return 3; }
int fmi3SetUInt8(void) { return 3; }
int fmi3SetInt16(void) { return 3; }
int fmi3SetUInt16(void) { return 3; }
int fmi3SetInt32(void) { return 3; }
int fmi3SetUInt32(void) { return 3; }
int fmi3SetInt64(void) { return 3; }
int fmi3SetUInt64(void) { return 3; }
int fmi3SetBoolean(void) { return 3; }
int fmi3SetString(void) { return 3; }
int fmi3SetBinary(void) { return 3; }
int fmi3SetClock(void) { return 3; }
int fmi3GetNumberOfVariableDependencies(void) { return 3; }
int fmi3GetVariableDependencies(void) { return 3; }
int fmi3GetDirectionalDerivative(void) { return 3; }
int fmi3GetAdjointDerivative(void) { return 3; }
int fmi3EnterConfigurationMode(void) { return 3; }
int fmi3ExitConfigurationMode(void) { return 3; }
int fmi3GetIntervalDecimal(void) { return 3; }
int fmi3GetIntervalFraction(void) { return 3; }
int fmi3GetShiftDecimal(void) { return 3; }
int fmi3GetShiftFraction(void) { return 3; }
int fmi3SetIntervalDecimal(void) { return 3; }
int fmi3SetIntervalFraction(void) { return 3; }
int fmi3SetShiftDecimal(void) { return 3; }
int fmi3SetShiftFraction(void) { return 3; }
int fmi3EvaluateDiscreteStates(void) { return 3; }
int fmi3UpdateDiscreteStates(void) { return 3; }
int fmi3EnterContinuousTimeMode(void) { return 3; }
int fmi3CompletedIntegratorStep(void) { return 3; }
int fmi3SetTime(void) { return 3; }
int fmi3SetContinuousStates(void) { return 3; }
int fmi3GetContinuousStateDerivatives(void) { return 3; }
int fmi3GetEventIndicators(void) { return 3; }
int fmi3GetContinuousStates(void) { return 3; }
int fmi3GetNominalsOfContinuousStates(void) { return 3; }
int fmi3GetNumberOfEventIndicators(void) { return 3; }
int fmi3GetNumberOfContinuousStates(void) { return 3; }
int fmi3EnterStepMode(void) { return 3; }
int fmi3GetOutputDerivatives(void) { return 3; }
int fmi3ActivateModelPartition(void) { return 3; }
