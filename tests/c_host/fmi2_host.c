/* A minimal FMI 2.0 co-simulation host for the tests: a native process that never loads Python itself.

   fmi2_host LIBRARY RESOURCE_URI GUID LOGGING COMMAND...

   dlopens LIBRARY, instantiates (loggingOn = LOGGING, 0 or 1) and runs the commands in order, printing one line
   per call ("CALL name status") and per logged message ("LOG status category message"). Its logger aborts
   (exit 134, like OMSimulator's, which builds a std::string from the category) when the category is NULL.

   Commands: setup | enter | exit | term | reset | free
             setr:VR:VALUE | getr:VR (prints "VALUE VR %.17g") | setb:VR:0|1 (a Boolean) | sets:VR:TEXT (a String)
             | step:T:H
             | steps:T:H:COUNT (COUNT steps of H)
             save (fmi2GetFMUstate) | restore (fmi2SetFMUstate) | timeit:T:H:COUNT:VR... (COUNT steps, reading
             the VRs after each; prints "TIME seconds") */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env;
    (void)instance;
    if (category == NULL) {
        printf("NULL-CATEGORY %s\n", message != NULL ? message : "(null)");
        fflush(stdout);
        abort();
    }
    printf("LOG %d %s %s\n", (int)status, category, message != NULL ? message : "(null)");
    fflush(stdout);
}

#define LOAD(name)                                                                  \
    name##TYPE* name = (name##TYPE*)dlsym(library, #name);                          \
    if (name == NULL) {                                                             \
        fprintf(stderr, "missing symbol %s\n", #name);                              \
        return 3;                                                                   \
    }

static double seconds(void)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)now.tv_sec + 1e-9 * (double)now.tv_nsec;
}

int main(int argc, char** argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: fmi2_host LIBRARY RESOURCE_URI GUID LOGGING COMMAND...\n");
        return 2;
    }
    void* library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 3;
    }
    LOAD(fmi2Instantiate)
    LOAD(fmi2FreeInstance)
    LOAD(fmi2SetupExperiment)
    LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode)
    LOAD(fmi2Terminate)
    LOAD(fmi2Reset)
    LOAD(fmi2SetReal)
    LOAD(fmi2SetBoolean)
    LOAD(fmi2SetString)
    LOAD(fmi2GetReal)
    LOAD(fmi2DoStep)
    LOAD(fmi2GetFMUstate)
    LOAD(fmi2SetFMUstate)
    LOAD(fmi2FreeFMUstate)

    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("host", fmi2CoSimulation, argv[3], argv[2], &callbacks, fmi2False,
                                      atoi(argv[4]) ? fmi2True : fmi2False);
    printf("CALL instantiate %s\n", c != NULL ? "ok" : "null");
    fflush(stdout);
    if (c == NULL) {
        return 0;
    }
    fmi2FMUstate state = NULL;
    int freed = 0;
    for (int i = 5; i < argc; ++i) {
        const char* command = argv[i];
        fmi2Status status = fmi2OK;
        if (strcmp(command, "setup") == 0) {
            status = fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
        } else if (strcmp(command, "enter") == 0) {
            status = fmi2EnterInitializationMode(c);
        } else if (strcmp(command, "exit") == 0) {
            status = fmi2ExitInitializationMode(c);
        } else if (strcmp(command, "term") == 0) {
            status = fmi2Terminate(c);
        } else if (strcmp(command, "reset") == 0) {
            status = fmi2Reset(c);
        } else if (strcmp(command, "free") == 0) {
            fmi2FreeInstance(c);
            freed = 1;
            printf("CALL free\n");
            break;
        } else if (strcmp(command, "save") == 0) {
            status = fmi2GetFMUstate(c, &state);
        } else if (strcmp(command, "restore") == 0) {
            status = fmi2SetFMUstate(c, state);
        } else if (strncmp(command, "setr:", 5) == 0) {
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(command + 5, NULL, 10);
            fmi2Real value = strtod(strchr(command + 5, ':') + 1, NULL);
            status = fmi2SetReal(c, &vr, 1, &value);
        } else if (strncmp(command, "setb:", 5) == 0) {
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(command + 5, NULL, 10);
            fmi2Boolean value = atoi(strchr(command + 5, ':') + 1) ? fmi2True : fmi2False;
            status = fmi2SetBoolean(c, &vr, 1, &value);
        } else if (strncmp(command, "sets:", 5) == 0) {
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(command + 5, NULL, 10);
            fmi2String value = strchr(command + 5, ':') + 1;
            status = fmi2SetString(c, &vr, 1, &value);
        } else if (strncmp(command, "getr:", 5) == 0) {
            fmi2ValueReference vr = (fmi2ValueReference)strtoul(command + 5, NULL, 10);
            fmi2Real value = 0.0;
            status = fmi2GetReal(c, &vr, 1, &value);
            if (status == fmi2OK) {
                printf("VALUE %u %.17g\n", vr, value);
            }
        } else if (strncmp(command, "step:", 5) == 0 || strncmp(command, "steps:", 6) == 0
                   || strncmp(command, "timeit:", 7) == 0) {
            char* rest = strchr(command, ':') + 1;
            double t = strtod(rest, &rest);
            double h = strtod(rest + 1, &rest);
            long count = *rest == ':' ? strtol(rest + 1, &rest, 10) : 1;
            fmi2ValueReference vrs[64];
            fmi2Real values[64];
            size_t nvr = 0;
            while (*rest == ':' && nvr < 64) {
                vrs[nvr++] = (fmi2ValueReference)strtoul(rest + 1, &rest, 10);
            }
            double started = seconds();
            for (long k = 0; k < count && status == fmi2OK; ++k) {
                status = fmi2DoStep(c, t + (double)k * h, h, fmi2True);
                if (nvr > 0 && status == fmi2OK) {
                    status = fmi2GetReal(c, vrs, nvr, values);
                }
            }
            if (strncmp(command, "timeit:", 7) == 0) {
                printf("TIME %.9g\n", seconds() - started);
            }
        } else {
            fprintf(stderr, "unknown command %s\n", command);
            return 2;
        }
        printf("CALL %s %d\n", command, (int)status);
        fflush(stdout);
    }
    if (!freed) {
        if (state != NULL) {
            fmi2FreeFMUstate(c, &state);
        }
        fmi2FreeInstance(c);
    }
    printf("END\n");
    return 0;
}
