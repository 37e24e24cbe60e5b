/* A plain C FMI 2.0 host, as a C tool chain would use an FMU: dlopen the binary, resolve the
 * functions by their standard names, run instantiate -> initialize -> steps -> free.
 *
 * usage: host BINARY GUID RESOURCE_URI RUNS STEPS VR_TAU1 VR_Q1 [STATES]
 * With STATES, each run also takes that many FMU states (every second one serialized and read
 * back into another) and frees none of them: fmi2FreeInstance must. Prints q_1 after the last
 * run with 17 significant digits. Exit status 0 on success. */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef unsigned int fmi2ValueReference;
typedef int fmi2Status;
typedef struct {
    void (*logger)(void *, const char *, fmi2Status, const char *, const char *, ...);
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, fmi2Status);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static void logger(void *env, const char *name, fmi2Status status, const char *category, const char *message, ...) {
    va_list args;
    (void)env;
    fprintf(stderr, "[%s %d %s] ", name, status, category);
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

static const char *names[] = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate", "fmi2FreeInstance",
    "fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode", "fmi2Terminate",
    "fmi2Reset", "fmi2GetReal", "fmi2GetInteger", "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal",
    "fmi2SetInteger", "fmi2SetBoolean", "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate",
    "fmi2FreeFMUstate", "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives",
    "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus", "fmi2GetStringStatus",
};

#define CHECK(call)                                                                \
    do {                                                                           \
        fmi2Status s_ = (call);                                                    \
        if (s_ != 0) {                                                             \
            fprintf(stderr, "%s returned %d\n", #call, s_);                       \
            return 1;                                                              \
        }                                                                          \
    } while (0)

int main(int argc, char **argv) {
    if (argc != 8 && argc != 9) {
        fprintf(stderr, "usage: host BINARY GUID RESOURCE_URI RUNS STEPS VR_TAU1 VR_Q1 [STATES]\n");
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 1;
    }
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        if (!dlsym(lib, names[i])) {
            fprintf(stderr, "missing symbol %s\n", names[i]);
            return 1;
        }
    }
    fmi2Component (*instantiate)(const char *, int, const char *, const char *, const fmi2CallbackFunctions *, int, int) =
        (fmi2Component(*)(const char *, int, const char *, const char *, const fmi2CallbackFunctions *, int, int))dlsym(lib, "fmi2Instantiate");
    void (*free_instance)(fmi2Component) = (void (*)(fmi2Component))dlsym(lib, "fmi2FreeInstance");
    fmi2Status (*setup)(fmi2Component, int, double, double, int, double) =
        (fmi2Status(*)(fmi2Component, int, double, double, int, double))dlsym(lib, "fmi2SetupExperiment");
    fmi2Status (*enter)(fmi2Component) = (fmi2Status(*)(fmi2Component))dlsym(lib, "fmi2EnterInitializationMode");
    fmi2Status (*exit_init)(fmi2Component) = (fmi2Status(*)(fmi2Component))dlsym(lib, "fmi2ExitInitializationMode");
    fmi2Status (*terminate)(fmi2Component) = (fmi2Status(*)(fmi2Component))dlsym(lib, "fmi2Terminate");
    fmi2Status (*set_real)(fmi2Component, const fmi2ValueReference *, size_t, const double *) =
        (fmi2Status(*)(fmi2Component, const fmi2ValueReference *, size_t, const double *))dlsym(lib, "fmi2SetReal");
    fmi2Status (*get_real)(fmi2Component, const fmi2ValueReference *, size_t, double *) =
        (fmi2Status(*)(fmi2Component, const fmi2ValueReference *, size_t, double *))dlsym(lib, "fmi2GetReal");
    fmi2Status (*do_step)(fmi2Component, double, double, int) = (fmi2Status(*)(fmi2Component, double, double, int))dlsym(lib, "fmi2DoStep");
    fmi2Status (*get_state)(fmi2Component, void **) = (fmi2Status(*)(fmi2Component, void **))dlsym(lib, "fmi2GetFMUstate");
    fmi2Status (*state_size)(fmi2Component, void *, size_t *) = (fmi2Status(*)(fmi2Component, void *, size_t *))dlsym(lib, "fmi2SerializedFMUstateSize");
    fmi2Status (*serialize)(fmi2Component, void *, char *, size_t) = (fmi2Status(*)(fmi2Component, void *, char *, size_t))dlsym(lib, "fmi2SerializeFMUstate");
    fmi2Status (*deserialize)(fmi2Component, const char *, size_t, void **) =
        (fmi2Status(*)(fmi2Component, const char *, size_t, void **))dlsym(lib, "fmi2DeSerializeFMUstate");
    int states = argc == 9 ? atoi(argv[8]) : 0;

    int runs = atoi(argv[4]), steps = atoi(argv[5]);
    fmi2ValueReference tau = (fmi2ValueReference)atoi(argv[6]), q = (fmi2ValueReference)atoi(argv[7]);
    fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};
    double q_last = 0.0;
    for (int r = 0; r < runs; r++) {
        fmi2Component c = instantiate("c-host", 1, argv[2], argv[3], &callbacks, 0, 0);
        if (!c) {
            fprintf(stderr, "fmi2Instantiate returned NULL\n");
            return 1;
        }
        CHECK(setup(c, 0, 0.0, 0.0, 0, 0.0));
        CHECK(enter(c));
        CHECK(exit_init(c));
        double torque = 2.5;
        CHECK(set_real(c, &tau, 1, &torque));
        for (int k = 0; k < steps; k++) CHECK(do_step(c, k * 1e-3, 1e-3, 1));
        CHECK(get_real(c, &q, 1, &q_last));
        for (int k = 0; k < states; k++) {
            void *state = NULL;
            CHECK(get_state(c, &state));
            if (k % 2 == 1) {
                size_t size = 0;
                CHECK(state_size(c, state, &size));
                char *bytes = malloc(size);
                CHECK(serialize(c, state, bytes, size));
                void *copy = NULL;
                CHECK(deserialize(c, bytes, size, &copy));
                free(bytes);
            }
        }
        CHECK(terminate(c));
        free_instance(c);
    }
    printf("%.17g\n", q_last);
    dlclose(lib);
    return 0;
}
