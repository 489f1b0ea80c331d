/* A co-simulation host that calls the native FMU as nobody should (issue 31): NULL instances and pointers, calls out
   of order, non-finite and huge numbers, forged state blobs. Built with -DFMI_VERSION=2 or 3, and with the
   sanitizers where the compiler has them (tests/native_host.py): a crash, an invalid access or undefined behaviour
   ends the process, which the tests see.

   trust_host LIBRARY GUID LOGGING COMMAND...

   Prints "CALL command status" per call (status -1: a function without one), "LOG status category message" per
   logged message (a NULL category aborts, as OMSimulator does), "VALUE vr value" per value read, then "END".

   Commands: setup:START[:STOP] (FMI 2.0: fmi2SetupExperiment; FMI 3.0: the start and stop of enter)
             enter | exit | term | reset | free | cancel (fmi2CancelStep) | status (the last successful time)
             setr:VR:VALUE | getr:VR | geta:VR:N (FMI 3.0: N values of one variable, u) | sets:VR:TEXT|NULL
             seti:VR:VALUE | geti:VR (an Integer; FMI 3.0: an Int32) | setb:VR:0|1 (a Boolean)
             step:T:H | save | restore | freestate | dump:PATH (the saved state serialized into PATH)
             load:PATH (PATH deserialized into the saved state) | poke:PATH (PATH's bytes over the saved state's
             memory) | debug:0|1
             deriv:VR:ORDER:VALUE (FMI 2.0: fmi2SetRealInputDerivatives of one variable)
             oderiv:VR:ORDER (FMI 2.0: fmi2GetRealOutputDerivatives of one variable)
             nullc (every function with a NULL instance) | nulla (functions with NULL pointer arguments) */
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if FMI_VERSION == 3
#include "fmi3Functions.h"
typedef fmi3Instance Instance;
typedef fmi3FMUState FMUState;
typedef fmi3Status Status;
typedef fmi3ValueReference ValueReference;
#define P(name) fmi3##name
#else
#include "fmi2Functions.h"
typedef fmi2Component Instance;
typedef fmi2FMUstate FMUState;
typedef fmi2Status Status;
typedef fmi2ValueReference ValueReference;
#define P(name) fmi2##name
#endif

static void* library;

static void* symbol(const char* name)
{
    void* found = dlsym(library, name);
    if (found == NULL) {
        fprintf(stderr, "missing symbol %s\n", name);
        exit(3);
    }
    return found;
}

#if FMI_VERSION == 3
#define FMI_NAME "3"
#define GET_STATE F(GetFMUState)
#define SET_STATE F(SetFMUState)
#define FREE_STATE F(FreeFMUState)
#define STATE_SIZE F(SerializedFMUStateSize)
#define SERIALIZE F(SerializeFMUState)
#define DESERIALIZE F(DeserializeFMUState)
#else
#define FMI_NAME "2"
#define GET_STATE F(GetFMUstate)
#define SET_STATE F(SetFMUstate)
#define FREE_STATE F(FreeFMUstate)
#define STATE_SIZE F(SerializedFMUstateSize)
#define SERIALIZE F(SerializeFMUstate)
#define DESERIALIZE F(DeSerializeFMUstate)
#endif
#define F(name) ((P(name##TYPE)*)symbol("fmi" FMI_NAME #name))

static void report(const char* category, int status, const char* message)
{
    if (category == NULL) {
        printf("NULL-CATEGORY %s\n", message != NULL ? message : "(null)");
        fflush(stdout);
        abort();
    }
    printf("LOG %d %s %s\n", status, category, message != NULL ? message : "(null)");
    fflush(stdout);
}

#if FMI_VERSION == 3
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env;
    report(category, (int)status, message);
}
#else
static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env;
    (void)instance;
    report(category, (int)status, message);
}
#endif

static void call(const char* command, int status)
{
    printf("CALL %s %d\n", command, status);
    fflush(stdout);
}

static Instance instantiate(const char* guid, int logging)
{
#if FMI_VERSION == 3
    return F(InstantiateCoSimulation)("host", guid, NULL, fmi3False, logging ? fmi3True : fmi3False, fmi3False,
                                      fmi3False, NULL, 0, NULL, logger, NULL);
#else
    static fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    return F(Instantiate)("host", fmi2CoSimulation, guid, "", &callbacks, fmi2False, logging ? fmi2True : fmi2False);
#endif
}

/* every function of the FMI version with a NULL instance: each must return an error (or, void, do nothing) */
static void null_instance(void)
{
    ValueReference vr = 0;
    double real = 0.0;
    FMUState state = NULL;
    size_t size = 0;
    char bytes[8] = {0};
#if FMI_VERSION == 3
    fmi3Boolean flag = fmi3False;
    fmi3Int32 i32 = 0;
    fmi3UInt64 u64 = 0;
    fmi3String text = NULL;
    call("nullc:fmi3SetDebugLogging", F(SetDebugLogging)(NULL, fmi3True, 0, NULL));
    call("nullc:fmi3EnterInitializationMode", F(EnterInitializationMode)(NULL, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    call("nullc:fmi3ExitInitializationMode", F(ExitInitializationMode)(NULL));
    call("nullc:fmi3EnterStepMode", F(EnterStepMode)(NULL));
    call("nullc:fmi3DoStep", F(DoStep)(NULL, 0.0, 0.1, fmi3True, &flag, &flag, &flag, &real));
    call("nullc:fmi3Terminate", F(Terminate)(NULL));
    call("nullc:fmi3Reset", F(Reset)(NULL));
    call("nullc:fmi3GetFloat64", F(GetFloat64)(NULL, &vr, 1, &real, 1));
    call("nullc:fmi3SetFloat64", F(SetFloat64)(NULL, &vr, 1, &real, 1));
    call("nullc:fmi3GetInt32", F(GetInt32)(NULL, &vr, 1, &i32, 1));
    call("nullc:fmi3GetUInt64", F(GetUInt64)(NULL, &vr, 1, &u64, 1));
    call("nullc:fmi3SetUInt64", F(SetUInt64)(NULL, &vr, 1, &u64, 1));
    call("nullc:fmi3GetBoolean", F(GetBoolean)(NULL, &vr, 1, &flag, 1));
    call("nullc:fmi3SetBoolean", F(SetBoolean)(NULL, &vr, 1, &flag, 1));
    call("nullc:fmi3GetString", F(GetString)(NULL, &vr, 1, &text, 1));
    call("nullc:fmi3SetString", F(SetString)(NULL, &vr, 1, &text, 1));
    call("nullc:fmi3GetFloat32", F(GetFloat32)(NULL, &vr, 0, NULL, 0));
    call("nullc:fmi3SetInt32", F(SetInt32)(NULL, &vr, 1, &i32, 1));
    call("nullc:fmi3GetFMUState", F(GetFMUState)(NULL, &state));
    call("nullc:fmi3SetFMUState", F(SetFMUState)(NULL, state));
    call("nullc:fmi3FreeFMUState", F(FreeFMUState)(NULL, &state));
    call("nullc:fmi3SerializedFMUStateSize", F(SerializedFMUStateSize)(NULL, state, &size));
    call("nullc:fmi3SerializeFMUState", F(SerializeFMUState)(NULL, state, (fmi3Byte*)bytes, sizeof bytes));
    call("nullc:fmi3DeserializeFMUState", F(DeserializeFMUState)(NULL, (fmi3Byte*)bytes, sizeof bytes, &state));
    call("nullc:fmi3GetDirectionalDerivative", F(GetDirectionalDerivative)(NULL, &vr, 1, &vr, 1, &real, 1, &real, 1));
    call("nullc:fmi3EnterEventMode", F(EnterEventMode)(NULL));
    call("nullc:fmi3GetNumberOfContinuousStates", F(GetNumberOfContinuousStates)(NULL, &size));
    call("nullc:fmi3SetTime", F(SetTime)(NULL, 0.0));
    F(FreeInstance)(NULL);
    call("nullc:fmi3FreeInstance", -1);
#else
    fmi2Integer integer = 0;
    fmi2Boolean flag = fmi2False;
    fmi2String text = NULL;
    fmi2Status status = fmi2OK;
    call("nullc:fmi2SetDebugLogging", F(SetDebugLogging)(NULL, fmi2True, 0, NULL));
    call("nullc:fmi2SetupExperiment", F(SetupExperiment)(NULL, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    call("nullc:fmi2EnterInitializationMode", F(EnterInitializationMode)(NULL));
    call("nullc:fmi2ExitInitializationMode", F(ExitInitializationMode)(NULL));
    call("nullc:fmi2Terminate", F(Terminate)(NULL));
    call("nullc:fmi2Reset", F(Reset)(NULL));
    call("nullc:fmi2GetReal", F(GetReal)(NULL, &vr, 1, &real));
    call("nullc:fmi2GetInteger", F(GetInteger)(NULL, &vr, 1, &integer));
    call("nullc:fmi2GetBoolean", F(GetBoolean)(NULL, &vr, 1, &flag));
    call("nullc:fmi2GetString", F(GetString)(NULL, &vr, 1, &text));
    call("nullc:fmi2SetReal", F(SetReal)(NULL, &vr, 1, &real));
    call("nullc:fmi2SetInteger", F(SetInteger)(NULL, &vr, 1, &integer));
    call("nullc:fmi2SetBoolean", F(SetBoolean)(NULL, &vr, 1, &flag));
    call("nullc:fmi2SetString", F(SetString)(NULL, &vr, 1, &text));
    call("nullc:fmi2GetFMUstate", F(GetFMUstate)(NULL, &state));
    call("nullc:fmi2SetFMUstate", F(SetFMUstate)(NULL, state));
    call("nullc:fmi2FreeFMUstate", F(FreeFMUstate)(NULL, &state));
    call("nullc:fmi2SerializedFMUstateSize", F(SerializedFMUstateSize)(NULL, state, &size));
    call("nullc:fmi2SerializeFMUstate", F(SerializeFMUstate)(NULL, state, bytes, sizeof bytes));
    call("nullc:fmi2DeSerializeFMUstate", F(DeSerializeFMUstate)(NULL, bytes, sizeof bytes, &state));
    call("nullc:fmi2GetDirectionalDerivative", F(GetDirectionalDerivative)(NULL, &vr, 1, &vr, 1, &real, &real));
    call("nullc:fmi2SetRealInputDerivatives", F(SetRealInputDerivatives)(NULL, &vr, 1, &integer, &real));
    call("nullc:fmi2GetRealOutputDerivatives", F(GetRealOutputDerivatives)(NULL, &vr, 1, &integer, &real));
    call("nullc:fmi2DoStep", F(DoStep)(NULL, 0.0, 0.1, fmi2True));
    call("nullc:fmi2CancelStep", F(CancelStep)(NULL));
    call("nullc:fmi2GetStatus", F(GetStatus)(NULL, fmi2DoStepStatus, &status));
    call("nullc:fmi2GetRealStatus", F(GetRealStatus)(NULL, fmi2LastSuccessfulTime, &real));
    call("nullc:fmi2GetIntegerStatus", F(GetIntegerStatus)(NULL, fmi2LastSuccessfulTime, &integer));
    call("nullc:fmi2GetBooleanStatus", F(GetBooleanStatus)(NULL, fmi2Terminated, &flag));
    call("nullc:fmi2GetStringStatus", F(GetStringStatus)(NULL, fmi2PendingStatus, &text));
    F(FreeInstance)(NULL);
    call("nullc:fmi2FreeInstance", -1);
#endif
}

/* functions of a valid instance handed NULL pointers: each must return an error with a logged reason */
static void null_arguments(Instance c, ValueReference vr)
{
    double real = 0.0;
    FMUState state = NULL;
    size_t size = 0;
    char bytes[16] = {0};
    const char* text = "implicit";
#if FMI_VERSION == 3
    fmi3Boolean flag = fmi3False;
    call("nulla:GetFloat64(vr)", F(GetFloat64)(c, NULL, 1, &real, 1));
    call("nulla:GetFloat64(values)", F(GetFloat64)(c, &vr, 1, NULL, 1));
    call("nulla:SetFloat64(vr)", F(SetFloat64)(c, NULL, 1, &real, 1));
    call("nulla:SetFloat64(values)", F(SetFloat64)(c, &vr, 1, NULL, 1));
    call("nulla:GetBoolean(values)", F(GetBoolean)(c, &vr, 1, NULL, 1));
    call("nulla:SetBoolean(values)", F(SetBoolean)(c, &vr, 1, NULL, 1));
    call("nulla:GetString(values)", F(GetString)(c, &vr, 1, NULL, 1));
    call("nulla:SetString(values)", F(SetString)(c, &vr, 1, NULL, 1));
    call("nulla:GetUInt64(values)", F(GetUInt64)(c, &vr, 1, NULL, 1));
    call("nulla:SetUInt64(values)", F(SetUInt64)(c, &vr, 1, NULL, 1));
    call("nulla:GetInt32(values)", F(GetInt32)(c, &vr, 1, NULL, 1));
    call("nulla:SetDebugLogging(categories)", F(SetDebugLogging)(c, fmi3True, 2, NULL));
    call("nulla:GetFMUState(state)", F(GetFMUState)(c, NULL));
    call("nulla:SetFMUState(state)", F(SetFMUState)(c, NULL));
    call("nulla:FreeFMUState(state)", F(FreeFMUState)(c, NULL));
    call("nulla:SerializedFMUStateSize(state)", F(SerializedFMUStateSize)(c, NULL, &size));
    call("nulla:DeserializeFMUState(bytes)", F(DeserializeFMUState)(c, NULL, 100, &state));
    call("nulla:DeserializeFMUState(state)", F(DeserializeFMUState)(c, (fmi3Byte*)bytes, sizeof bytes, NULL));
    call("nulla:DoStep(flags)", F(DoStep)(c, 0.0, 0.1, fmi3True, NULL, NULL, NULL, NULL));
    (void)flag;
    (void)text;
    if (F(GetFMUState)(c, &state) == fmi3OK) { /* a valid state: the size and the bytes */
        call("nulla:SerializedFMUStateSize(size)", F(SerializedFMUStateSize)(c, state, NULL));
        call("nulla:SerializeFMUState(state)", F(SerializeFMUState)(c, NULL, (fmi3Byte*)bytes, sizeof bytes));
        call("nulla:SerializeFMUState(bytes)", F(SerializeFMUState)(c, state, NULL, 1 << 20));
        F(FreeFMUState)(c, &state);
    }
#else
    fmi2Integer integer = 0;
    fmi2Boolean flag = fmi2False;
    fmi2String strings[1] = {NULL};
    call("nulla:GetReal(vr)", F(GetReal)(c, NULL, 1, &real));
    call("nulla:GetReal(value)", F(GetReal)(c, &vr, 1, NULL));
    call("nulla:SetReal(vr)", F(SetReal)(c, NULL, 1, &real));
    call("nulla:SetReal(value)", F(SetReal)(c, &vr, 1, NULL));
    call("nulla:GetInteger(value)", F(GetInteger)(c, &vr, 1, NULL));
    call("nulla:GetBoolean(value)", F(GetBoolean)(c, &vr, 1, NULL));
    call("nulla:SetBoolean(value)", F(SetBoolean)(c, &vr, 1, NULL));
    call("nulla:GetString(value)", F(GetString)(c, &vr, 1, NULL));
    call("nulla:SetString(value)", F(SetString)(c, &vr, 1, NULL));
    call("nulla:SetString(value[0])", F(SetString)(c, &vr, 1, strings));
    call("nulla:SetDebugLogging(categories)", F(SetDebugLogging)(c, fmi2True, 2, NULL));
    call("nulla:GetFMUstate(state)", F(GetFMUstate)(c, NULL));
    call("nulla:SetFMUstate(state)", F(SetFMUstate)(c, NULL));
    call("nulla:FreeFMUstate(state)", F(FreeFMUstate)(c, NULL));
    call("nulla:SerializedFMUstateSize(state)", F(SerializedFMUstateSize)(c, NULL, &size));
    call("nulla:DeSerializeFMUstate(bytes)", F(DeSerializeFMUstate)(c, NULL, 100, &state));
    call("nulla:DeSerializeFMUstate(state)", F(DeSerializeFMUstate)(c, bytes, sizeof bytes, NULL));
    call("nulla:GetRealStatus(value)", F(GetRealStatus)(c, fmi2LastSuccessfulTime, NULL));
    call("nulla:GetBooleanStatus(value)", F(GetBooleanStatus)(c, fmi2Terminated, NULL));
    call("nulla:GetStatus(value)", F(GetStatus)(c, fmi2DoStepStatus, NULL));
    call("nulla:SetRealInputDerivatives(vr)", F(SetRealInputDerivatives)(c, NULL, 1, &integer, &real));
    call("nulla:SetRealInputDerivatives(order)", F(SetRealInputDerivatives)(c, &vr, 1, NULL, &real));
    call("nulla:SetRealInputDerivatives(value)", F(SetRealInputDerivatives)(c, &vr, 1, &integer, NULL));
    call("nulla:GetRealOutputDerivatives(vr)", F(GetRealOutputDerivatives)(c, NULL, 1, &integer, &real));
    call("nulla:GetRealOutputDerivatives(order)", F(GetRealOutputDerivatives)(c, &vr, 1, NULL, &real));
    call("nulla:GetRealOutputDerivatives(value)", F(GetRealOutputDerivatives)(c, &vr, 1, &integer, NULL));
    call("nulla:GetDirectionalDerivative(unknowns)", F(GetDirectionalDerivative)(c, NULL, 1, &vr, 1, &real, &real));
    call("nulla:GetDirectionalDerivative(knowns)", F(GetDirectionalDerivative)(c, &vr, 1, NULL, 1, &real, &real));
    call("nulla:GetDirectionalDerivative(seed)", F(GetDirectionalDerivative)(c, &vr, 1, &vr, 1, NULL, &real));
    call("nulla:GetDirectionalDerivative(sensitivity)", F(GetDirectionalDerivative)(c, &vr, 1, &vr, 1, &real, NULL));
    (void)integer;
    (void)flag;
    (void)text;
    if (F(GetFMUstate)(c, &state) == fmi2OK) { /* a valid state: the size and the bytes */
        call("nulla:SerializedFMUstateSize(size)", F(SerializedFMUstateSize)(c, state, NULL));
        call("nulla:SerializeFMUstate(state)", F(SerializeFMUstate)(c, NULL, bytes, sizeof bytes));
        call("nulla:SerializeFMUstate(bytes)", F(SerializeFMUstate)(c, state, NULL, 1 << 20));
        F(FreeFMUstate)(c, &state);
    }
#endif
}

static int dump(Instance c, FMUState state, const char* path)
{
    size_t size = 0;
    char* bytes;
    FILE* file;
    int status = (int)STATE_SIZE(c, state, &size);
    if (status != 0)
        return status;
    bytes = (char*)malloc(size);
    status = (int)SERIALIZE(c, state, (void*)bytes, size);
    if (status == 0 && (file = fopen(path, "wb")) != NULL) {
        fwrite(bytes, 1, size, file);
        fclose(file);
    }
    free(bytes);
    return status;
}

static int load(Instance c, FMUState* state, const char* path)
{
    FILE* file = fopen(path, "rb");
    char* bytes;
    long size;
    int status;
    if (file == NULL)
        return 99;
    fseek(file, 0, SEEK_END);
    size = ftell(file);
    fseek(file, 0, SEEK_SET);
    bytes = (char*)malloc(size > 0 ? (size_t)size : 1);
    if (fread(bytes, 1, (size_t)size, file) != (size_t)size)
        size = 0;
    fclose(file);
    status = (int)DESERIALIZE(c, (void*)bytes, (size_t)size, state);
    free(bytes);
    return status;
}

/* PATH's bytes written over the memory of the saved state (a master whose memory was corrupted): what
   SetFMUstate must check again */
static int poke(Instance c, FMUState state, const char* path)
{
    size_t size = 0;
    long length;
    FILE* file = fopen(path, "rb");
    if (file == NULL || STATE_SIZE(c, state, &size) != 0) {
        if (file != NULL)
            fclose(file);
        return 99;
    }
    fseek(file, 0, SEEK_END);
    length = ftell(file);
    fseek(file, 0, SEEK_SET);
    if (length != (long)size || fread(state, 1, size, file) != size) {
        fclose(file);
        return 97;
    }
    fclose(file);
    return 0;
}

int main(int argc, char** argv)
{
    Instance c;
    FMUState state = NULL;
    double start = 0.0, stop = 0.0;
    int stop_defined = 0, freed = 0, i;
    if (argc < 4) {
        fprintf(stderr, "usage: trust_host LIBRARY GUID LOGGING COMMAND...\n");
        return 2;
    }
    library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 3;
    }
    c = instantiate(argv[2], atoi(argv[3]));
    printf("CALL instantiate %s\n", c != NULL ? "ok" : "null");
    fflush(stdout);
    if (c == NULL)
        return 0;
    for (i = 4; i < argc; ++i) {
        const char* command = argv[i];
        const char* rest = strchr(command, ':') ? strchr(command, ':') + 1 : "";
        int status = 0;
        if (strcmp(command, "free") == 0) {
            if (state != NULL)
                FREE_STATE(c, &state);
            F(FreeInstance)(c);
            freed = 1;
            call(command, -1);
            break;
        } else if (strncmp(command, "setup:", 6) == 0) {
            char* end;
            start = strtod(rest, &end);
            stop_defined = *end == ':';
            stop = stop_defined ? strtod(end + 1, NULL) : 0.0;
#if FMI_VERSION == 3
            status = 0; /* the start and stop of fmi3EnterInitializationMode */
#else
            status = F(SetupExperiment)(c, fmi2False, 0.0, start, stop_defined ? fmi2True : fmi2False, stop);
#endif
        } else if (strcmp(command, "enter") == 0) {
#if FMI_VERSION == 3
            status = F(EnterInitializationMode)(c, fmi3False, 0.0, start, stop_defined ? fmi3True : fmi3False, stop);
#else
            status = F(EnterInitializationMode)(c);
#endif
        } else if (strcmp(command, "exit") == 0) {
            status = F(ExitInitializationMode)(c);
        } else if (strcmp(command, "term") == 0) {
            status = F(Terminate)(c);
        } else if (strcmp(command, "reset") == 0) {
            status = F(Reset)(c);
        } else if (strcmp(command, "cancel") == 0) {
#if FMI_VERSION == 3
            status = F(EnterStepMode)(c); /* FMI 3.0 has no cancel; the call this FMU has no use for */
#else
            status = F(CancelStep)(c);
#endif
        } else if (strcmp(command, "status") == 0) {
#if FMI_VERSION == 3
            status = 3;
#else
            double time = 0.0;
            status = F(GetRealStatus)(c, fmi2LastSuccessfulTime, &time);
            if (status == 0)
                printf("STATUS %.17g\n", time);
#endif
        } else if (strncmp(command, "debug:", 6) == 0) {
            status = F(SetDebugLogging)(c, atoi(rest) ? 1 : 0, 0, NULL);
#if FMI_VERSION == 2
        } else if (strncmp(command, "deriv:", 6) == 0) { /* deriv:VR:ORDER:VALUE, fmi2SetRealInputDerivatives */
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            const char* after = strchr(rest, ':') + 1;
            fmi2Integer order = (fmi2Integer)strtol(after, NULL, 10);
            double value = strtod(strchr(after, ':') + 1, NULL);
            status = F(SetRealInputDerivatives)(c, &vr, 1, &order, &value);
        } else if (strncmp(command, "oderiv:", 7) == 0) { /* oderiv:VR:ORDER, fmi2GetRealOutputDerivatives */
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            fmi2Integer order = (fmi2Integer)strtol(strchr(rest, ':') + 1, NULL, 10);
            double value = 0.0;
            status = F(GetRealOutputDerivatives)(c, &vr, 1, &order, &value);
            if (status == fmi2OK)
                printf("VALUE %u %.17g\n", vr, value);
#endif
        } else if (strncmp(command, "setr:", 5) == 0) {
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            double value = strtod(strchr(rest, ':') + 1, NULL);
#if FMI_VERSION == 3
            status = F(SetFloat64)(c, &vr, 1, &value, 1);
#else
            status = F(SetReal)(c, &vr, 1, &value);
#endif
        } else if (strncmp(command, "getr:", 5) == 0) {
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            double value = 0.0;
#if FMI_VERSION == 3
            status = F(GetFloat64)(c, &vr, 1, &value, 1);
#else
            status = F(GetReal)(c, &vr, 1, &value);
#endif
            if (status == 0)
                printf("VALUE %u %.17g\n", vr, value);
        } else if (strncmp(command, "seti:", 5) == 0) {
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            int value = (int)strtol(strchr(rest, ':') + 1, NULL, 10);
#if FMI_VERSION == 3
            fmi3Int32 values[1];
            values[0] = (fmi3Int32)value;
            status = F(SetInt32)(c, &vr, 1, values, 1);
#else
            fmi2Integer values[1];
            values[0] = (fmi2Integer)value;
            status = F(SetInteger)(c, &vr, 1, values);
#endif
        } else if (strncmp(command, "setb:", 5) == 0) {
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            int value = atoi(strchr(rest, ':') + 1) != 0;
#if FMI_VERSION == 3
            fmi3Boolean values[1];
            values[0] = value ? fmi3True : fmi3False;
            status = F(SetBoolean)(c, &vr, 1, values, 1);
#else
            fmi2Boolean values[1];
            values[0] = value ? fmi2True : fmi2False;
            status = F(SetBoolean)(c, &vr, 1, values);
#endif
        } else if (strncmp(command, "geti:", 5) == 0) {
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
#if FMI_VERSION == 3
            fmi3Int32 values[1] = {0};
            status = F(GetInt32)(c, &vr, 1, values, 1);
#else
            fmi2Integer values[1] = {0};
            status = F(GetInteger)(c, &vr, 1, values);
#endif
            if (status == 0)
                printf("VALUE %u %d\n", vr, (int)values[0]);
        } else if (strncmp(command, "geta:", 5) == 0) {
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            size_t n = (size_t)strtoul(strchr(rest, ':') + 1, NULL, 10), j;
            double* values = (double*)calloc(n + 1, sizeof(double));
#if FMI_VERSION == 3
            status = F(GetFloat64)(c, &vr, 1, values, n);
#else
            status = F(GetReal)(c, &vr, 1, values);
#endif
            for (j = 0; status == 0 && j < n; j++)
                printf("VALUE %u %.17g\n", vr, values[j]);
            free(values);
        } else if (strncmp(command, "sets:", 5) == 0) {
            ValueReference vr = (ValueReference)strtoul(rest, NULL, 10);
            const char* text = strchr(rest, ':') + 1;
            const char* values[1];
            values[0] = strcmp(text, "NULL") == 0 ? NULL : text;
#if FMI_VERSION == 3
            status = F(SetString)(c, &vr, 1, values, 1);
#else
            status = F(SetString)(c, &vr, 1, values);
#endif
        } else if (strncmp(command, "step:", 5) == 0) {
            char* end;
            double t = strtod(rest, &end);
            double h = strtod(end + 1, NULL);
#if FMI_VERSION == 3
            fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
            double last = 0.0;
            status = F(DoStep)(c, t, h, fmi3True, &event, &terminate, &early, &last);
#else
            status = F(DoStep)(c, t, h, fmi2True);
#endif
        } else if (strcmp(command, "save") == 0) {
            status = GET_STATE(c, &state);
        } else if (strcmp(command, "restore") == 0) {
            status = SET_STATE(c, state);
        } else if (strcmp(command, "freestate") == 0) {
            status = FREE_STATE(c, &state);
        } else if (strncmp(command, "dump:", 5) == 0) {
            status = state != NULL ? dump(c, state, rest) : 98;
        } else if (strncmp(command, "load:", 5) == 0) {
            status = load(c, &state, rest);
        } else if (strncmp(command, "poke:", 5) == 0) {
            status = state != NULL ? poke(c, state, rest) : 98;
        } else if (strcmp(command, "nullc") == 0) {
            null_instance();
        } else if (strncmp(command, "nulla:", 6) == 0) {
            null_arguments(c, (ValueReference)strtoul(rest, NULL, 10));
        } else {
            fprintf(stderr, "unknown command %s\n", command);
            return 2;
        }
        call(command, status);
    }
    if (!freed) {
        if (state != NULL)
            FREE_STATE(c, &state);
        F(FreeInstance)(c);
    }
    printf("END\n");
    return 0;
}
