/* The host of the cross-platform tests (tests/fmu/native/test_platforms.py): built for the FMU's other platforms (mingw-w64 for
   win64 under wine, aarch64-linux-gnu-gcc for aarch64-linux under qemu-user), FMI 2.0 or 3.0 (-DFMI_VERSION=2|3).

   cross_host LIBRARY TOKEN RESOURCE_URI STEPPER_VR STEPPER F_VR OUT_VR,OUT_VR,... [noload:VR] [time:COUNT:H:F]
   (noload:VR: the Boolean VR, scene_load, set false in initialization mode: the force is F alone)

   Instantiates, sets the stepper (a String parameter) in initialization mode, then, from standard input, one line
   "H F" per communication step (each double as the 16 hex digits of its IEEE bits, so that no printf or strtod of
   the platform's C library rounds them): sets F, steps by H from the time reached, and prints the outputs as one
   line "OUT" followed by their bits in hex. With time:COUNT:H:F (decimal), instead: COUNT steps of H under F,
   reading the outputs after each, and prints "TIME seconds". Any status but OK is printed ("STATUS call status")
   and ends the run with exit 1. */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
static void* open_library(const char* path) { return (void*)LoadLibraryA(path); }
static void* find(void* library, const char* name) { return (void*)GetProcAddress((HMODULE)library, name); }
static double seconds(void)
{
    LARGE_INTEGER now, frequency;
    QueryPerformanceCounter(&now);
    QueryPerformanceFrequency(&frequency);
    return (double)now.QuadPart / (double)frequency.QuadPart;
}
#else
#include <dlfcn.h>
#include <time.h>
static void* open_library(const char* path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void* find(void* library, const char* name) { return dlsym(library, name); }
static double seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}
#endif

#if FMI_VERSION == 3
#include "fmi3Functions.h"
typedef fmi3ValueReference ValueReference;
#define OK fmi3OK
#else
#include "fmi2Functions.h"
typedef fmi2ValueReference ValueReference;
#define OK fmi2OK
#endif

static void* library;

static void* symbol(const char* name)
{
    void* found = find(library, name);
    if (found == NULL) {
        fprintf(stderr, "missing symbol %s\n", name);
        exit(3);
    }
    return found;
}

#define CHECK(call, what)                                      \
    do {                                                       \
        int status_ = (int)(call);                             \
        if (status_ != OK) {                                   \
            printf("STATUS %s %d\n", what, status_);          \
            return 1;                                          \
        }                                                      \
    } while (0)

static double from_bits(const char* text, char** end)
{
    uint64_t bits = (uint64_t)strtoull(text, end, 16);
    double value;
    memcpy(&value, &bits, sizeof value);
    return value;
}

static void print_bits(const double* values, size_t count)
{
    printf("OUT");
    for (size_t i = 0; i < count; ++i) {
        uint64_t bits;
        memcpy(&bits, &values[i], sizeof bits);
        printf(" %016" PRIx64, bits);
    }
    printf("\n");
}

#if FMI_VERSION == 3
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env;
    fprintf(stderr, "LOG %d %s %s\n", (int)status, category ? category : "(null)", message ? message : "(null)");
}
#else
#include <stdarg.h>
static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env;
    (void)instance;
    fprintf(stderr, "LOG %d %s %s\n", (int)status, category ? category : "(null)", message ? message : "(null)");
}
#endif

int main(int argc, char** argv)
{
    if (argc < 8) {
        fprintf(stderr, "usage: cross_host LIBRARY TOKEN RESOURCE_URI STEPPER_VR STEPPER F_VR OUT_VRS [noload:VR] "
                "[time:N:H:F]\n");
        return 2;
    }
    library = open_library(argv[1]);
    if (library == NULL) {
        fprintf(stderr, "cannot load %s\n", argv[1]);
        return 3;
    }
    ValueReference stepper_vr = (ValueReference)strtoul(argv[4], NULL, 10);
    ValueReference force_vr = (ValueReference)strtoul(argv[6], NULL, 10);
    ValueReference outputs[64];
    double values[64];
    size_t count = 0;
    for (char* rest = argv[7]; *rest && count < 64; rest += *rest == ',') {
        outputs[count++] = (ValueReference)strtoul(rest, &rest, 10);
    }
    const char* stepper = argv[5];
    int unloaded = argc > 8 && strncmp(argv[8], "noload:", 7) == 0; /* scene_load set false */
    ValueReference load_vr = unloaded ? (ValueReference)strtoul(argv[8] + 7, NULL, 10) : 0;
    char** more = argv + 8 + unloaded; /* the optional time:COUNT:H:F */
    int n_more = argc - 8 - unloaded;
#if FMI_VERSION == 3
    fmi3InstanceEnvironment none = NULL;
    fmi3Instance c = ((fmi3InstantiateCoSimulationTYPE*)symbol("fmi3InstantiateCoSimulation"))(
        "cross", argv[2], argv[3], fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, none, logger, NULL);
    if (c == NULL) {
        printf("STATUS instantiate null\n");
        return 1;
    }
    CHECK(((fmi3EnterInitializationModeTYPE*)symbol("fmi3EnterInitializationMode"))(c, fmi3False, 0.0, 0.0,
                                                                                        fmi3False, 0.0),
          "enter");
    CHECK(((fmi3SetStringTYPE*)symbol("fmi3SetString"))(c, &stepper_vr, 1, &stepper, 1), "stepper");
    fmi3Boolean no_load = fmi3False;
    if (unloaded)
        CHECK(((fmi3SetBooleanTYPE*)symbol("fmi3SetBoolean"))(c, &load_vr, 1, &no_load, 1), "scene_load");
    CHECK(((fmi3ExitInitializationModeTYPE*)symbol("fmi3ExitInitializationMode"))(c), "exit");
    fmi3SetFloat64TYPE* set_real = (fmi3SetFloat64TYPE*)symbol("fmi3SetFloat64");
    fmi3GetFloat64TYPE* get_real = (fmi3GetFloat64TYPE*)symbol("fmi3GetFloat64");
    fmi3DoStepTYPE* do_step = (fmi3DoStepTYPE*)symbol("fmi3DoStep");
#define SET_FORCE(value) set_real(c, &force_vr, 1, &(value), 1)
#define GET_OUTPUTS() get_real(c, outputs, count, values, count)
    fmi3Boolean event, terminate, early;
    fmi3Float64 reached;
#define STEP(t, h) do_step(c, (t), (h), fmi3True, &event, &terminate, &early, &reached)
#else
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = ((fmi2InstantiateTYPE*)symbol("fmi2Instantiate"))("cross", fmi2CoSimulation, argv[2], argv[3],
                                                                      &callbacks, fmi2False, fmi2False);
    if (c == NULL) {
        printf("STATUS instantiate null\n");
        return 1;
    }
    CHECK(((fmi2SetupExperimentTYPE*)symbol("fmi2SetupExperiment"))(c, fmi2False, 0.0, 0.0, fmi2False, 0.0),
          "setup");
    CHECK(((fmi2EnterInitializationModeTYPE*)symbol("fmi2EnterInitializationMode"))(c), "enter");
    CHECK(((fmi2SetStringTYPE*)symbol("fmi2SetString"))(c, &stepper_vr, 1, &stepper), "stepper");
    fmi2Boolean no_load = fmi2False;
    if (unloaded)
        CHECK(((fmi2SetBooleanTYPE*)symbol("fmi2SetBoolean"))(c, &load_vr, 1, &no_load), "scene_load");
    CHECK(((fmi2ExitInitializationModeTYPE*)symbol("fmi2ExitInitializationMode"))(c), "exit");
    fmi2SetRealTYPE* set_real = (fmi2SetRealTYPE*)symbol("fmi2SetReal");
    fmi2GetRealTYPE* get_real = (fmi2GetRealTYPE*)symbol("fmi2GetReal");
    fmi2DoStepTYPE* do_step = (fmi2DoStepTYPE*)symbol("fmi2DoStep");
#define SET_FORCE(value) set_real(c, &force_vr, 1, &(value))
#define GET_OUTPUTS() get_real(c, outputs, count, values)
#define STEP(t, h) do_step(c, (t), (h), fmi2True)
#endif
    double t = 0.0;
    if (n_more > 0 && strncmp(more[0], "time:", 5) == 0) {
        char* rest = more[0] + 5;
        long steps = strtol(rest, &rest, 10);
        double h = strtod(rest + 1, &rest);
        double force = strtod(rest + 1, &rest);
        CHECK(SET_FORCE(force), "force");
        double started = seconds();
        for (long k = 0; k < steps; ++k) {
            CHECK(STEP(t + (double)k * h, h), "step");
            CHECK(GET_OUTPUTS(), "outputs");
        }
        printf("TIME %.9g\n", seconds() - started);
        return 0;
    }
    char line[256];
    while (fgets(line, sizeof line, stdin) != NULL) {
        char* rest = line;
        double h = from_bits(rest, &rest);
        double force = from_bits(rest, &rest);
        CHECK(SET_FORCE(force), "force");
        CHECK(STEP(t, h), "step");
        t += h;
        CHECK(GET_OUTPUTS(), "outputs");
        print_bits(values, count);
    }
    fflush(stdout);
    return 0;
}
