/* A minimal FMI 2.0 Co-Simulation host for running an FMU's binary of another platform
 * (win64 under wine, aarch64 Linux under qemu) and comparing its results with linux64's.
 *
 *   fmu_host LIBRARY < SCENARIO
 *
 * SCENARIO, one command per line:
 *   instantiate NAME GUID URI...   fmi2Instantiate (Co-Simulation); URI is the rest of the line
 *   setup T0 STOP                  fmi2SetupExperiment, fmi2EnterInitializationMode, fmi2ExitInitializationMode
 *   real VR VALUE                  fmi2SetReal of one variable
 *   step T H                       fmi2DoStep
 *   get VR...                      fmi2GetReal; prints the values, %.17g, on one line
 *   free                           fmi2Terminate, fmi2FreeInstance
 * Prints "instantiated" or "instantiate failed"; any other failed call ends the run with exit
 * status 1 and says which. The FMU's log messages go to stderr. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _WIN32
#include <windows.h>
typedef HMODULE library_t;
static library_t open_library(const char *path) { return LoadLibraryA(path); }
static void *symbol(library_t l, const char *name) { return (void *)GetProcAddress(l, name); }
static const char *library_error(void) {
    static char text[64];
    snprintf(text, sizeof text, "error %lu", (unsigned long)GetLastError());
    return text;
}
#else
#include <dlfcn.h>
typedef void *library_t;
static library_t open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(library_t l, const char *name) { return dlsym(l, name); }
static const char *library_error(void) { return dlerror(); }
#endif

typedef void *component_t;
typedef struct {
    void (*logger)(void *, const char *, int, const char *, const char *, ...);
    void *(*allocate_memory)(size_t, size_t);
    void (*free_memory)(void *);
    void (*step_finished)(void *, int);
    void *environment;
} callbacks_t;

typedef component_t (*instantiate_t)(const char *, int, const char *, const char *, const callbacks_t *, int, int);
typedef int (*setup_t)(component_t, int, double, double, int, double);
typedef int (*component_call_t)(component_t);
typedef void (*free_t)(component_t);
typedef int (*reals_t)(component_t, const unsigned int *, size_t, double *);
typedef int (*set_reals_t)(component_t, const unsigned int *, size_t, const double *);
typedef int (*step_t)(component_t, double, double, int);

static void logger(void *env, const char *name, int status, const char *category, const char *message, ...) {
    va_list args;
    (void)env;
    fprintf(stderr, "[%s] status %d, %s: ", name, status, category);
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

static void *need(library_t l, const char *name) {
    void *f = symbol(l, name);
    if (!f) {
        fprintf(stderr, "the library does not export %s\n", name);
        exit(1);
    }
    return f;
}

static void check(int status, const char *call, int line) {
    if (status != 0) {
        fprintf(stderr, "scenario line %d: %s returned status %d\n", line, call, status);
        exit(1);
    }
}

int main(int argc, char **argv) {
    char text[8192];
    int line = 0;
    component_t c = NULL;
    library_t l;
    callbacks_t callbacks = {logger, calloc, free, NULL, NULL};
    if (argc != 2) {
        fprintf(stderr, "usage: %s LIBRARY < SCENARIO\n", argv[0]);
        return 2;
    }
    l = open_library(argv[1]);
    if (!l) {
        fprintf(stderr, "cannot load %s: %s\n", argv[1], library_error());
        return 1;
    }
    instantiate_t instantiate = (instantiate_t)need(l, "fmi2Instantiate");
    setup_t setup = (setup_t)need(l, "fmi2SetupExperiment");
    component_call_t enter = (component_call_t)need(l, "fmi2EnterInitializationMode");
    component_call_t leave = (component_call_t)need(l, "fmi2ExitInitializationMode");
    component_call_t terminate = (component_call_t)need(l, "fmi2Terminate");
    free_t free_instance = (free_t)need(l, "fmi2FreeInstance");
    set_reals_t set_real = (set_reals_t)need(l, "fmi2SetReal");
    reals_t get_real = (reals_t)need(l, "fmi2GetReal");
    step_t do_step = (step_t)need(l, "fmi2DoStep");
    while (fgets(text, sizeof text, stdin)) {
        char command[32];
        int used = 0;
        line++;
        text[strcspn(text, "\r\n")] = 0;
        if (sscanf(text, "%31s %n", command, &used) < 1) continue;
        const char *rest = text + used;
        if (!strcmp(command, "instantiate")) {
            char name[256], guid[256];
            int taken = 0;
            if (sscanf(rest, "%255s %255s %n", name, guid, &taken) < 2) goto bad;
            c = instantiate(name, 1, guid, rest + taken, &callbacks, 0, 0);
            puts(c ? "instantiated" : "instantiate failed");
            if (!c) return 0;
        } else if (!strcmp(command, "setup")) {
            double t0, stop;
            if (!c || sscanf(rest, "%lf %lf", &t0, &stop) != 2) goto bad;
            check(setup(c, 0, 0.0, t0, 1, stop), "fmi2SetupExperiment", line);
            check(enter(c), "fmi2EnterInitializationMode", line);
            check(leave(c), "fmi2ExitInitializationMode", line);
        } else if (!strcmp(command, "real")) {
            unsigned int vr;
            double value;
            if (!c || sscanf(rest, "%u %lf", &vr, &value) != 2) goto bad;
            check(set_real(c, &vr, 1, &value), "fmi2SetReal", line);
        } else if (!strcmp(command, "step")) {
            double t, h;
            if (!c || sscanf(rest, "%lf %lf", &t, &h) != 2) goto bad;
            check(do_step(c, t, h, 1), "fmi2DoStep", line);
        } else if (!strcmp(command, "get")) {
            unsigned int vr;
            int taken = 0;
            if (!c) goto bad;
            while (sscanf(rest, "%u %n", &vr, &taken) == 1) {
                double value;
                check(get_real(c, &vr, 1, &value), "fmi2GetReal", line);
                printf("%.17g ", value);
                rest += taken;
            }
            putchar('\n');
        } else if (!strcmp(command, "free")) {
            if (!c) goto bad;
            check(terminate(c), "fmi2Terminate", line);
            free_instance(c);
            c = NULL;
        } else {
            goto bad;
        }
    }
    return 0;
bad:
    fprintf(stderr, "scenario line %d: cannot run \"%s\"\n", line, text);
    return 2;
}
