/* A minimal FMI 2.0 Co-Simulation host in C for the leak check under valgrind:
 * loads the FMU binary with dlopen, runs many instantiate/step/free cycles (including the
 * error, discard and FMU-state paths), unloads and reloads the library every 100 cycles
 * (checking that it really leaves the process), and reports. With a thread count, that many
 * threads do it at once, each with its own handles, sharing the cycles.
 *
 *   leak_host <path/to/StewartPlatform.so> <GUID> [cycles] [threads]
 */
#include <dlfcn.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef void *fmi2Component;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef int fmi2Status;
typedef int fmi2Boolean;
typedef const char *fmi2String;
typedef void (*fmi2CallbackLogger)(void *, fmi2String, fmi2Status, fmi2String, fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, fmi2Status);
    void *componentEnvironment;
} fmi2CallbackFunctions;

static unsigned long messages = 0; /* approximate with threads: only counted */

/* The component environment: when armed, the logger frees the instance from inside the
 * callback on the next error message (a host tearing down on error). */
typedef struct {
    void (*free_instance)(void *);
    void *component;
    int armed;
} Environment;

static void logger(void *env, fmi2String name, fmi2Status status, fmi2String category, fmi2String message, ...) {
    char buffer[4096];
    va_list args;
    va_start(args, message);
    vsnprintf(buffer, sizeof buffer, message, args); /* what FMPy and FMI Library do */
    va_end(args);
    (void)name; (void)category;
    __atomic_fetch_add(&messages, 1, __ATOMIC_RELAXED);
    Environment *e = env;
    if (e && e->armed && status == 3) {
        e->armed = 0;
        e->free_instance(e->component);
    }
}

#define LOAD(name) name##_t name = (name##_t)dlsym(lib, #name); if (!name) { fprintf(stderr, "missing %s\n", #name); return 2; }

typedef fmi2Component (*fmi2Instantiate_t)(fmi2String, int, fmi2String, fmi2String, const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
typedef void (*fmi2FreeInstance_t)(fmi2Component);
typedef fmi2Status (*fmi2SetupExperiment_t)(fmi2Component, fmi2Boolean, double, double, fmi2Boolean, double);
typedef fmi2Status (*fmi2EnterInitializationMode_t)(fmi2Component);
typedef fmi2Status (*fmi2ExitInitializationMode_t)(fmi2Component);
typedef fmi2Status (*fmi2Terminate_t)(fmi2Component);
typedef fmi2Status (*fmi2Reset_t)(fmi2Component);
typedef fmi2Status (*fmi2SetReal_t)(fmi2Component, const fmi2ValueReference *, size_t, const double *);
typedef fmi2Status (*fmi2SetBoolean_t)(fmi2Component, const fmi2ValueReference *, size_t, const fmi2Boolean *);
typedef fmi2Status (*fmi2GetReal_t)(fmi2Component, const fmi2ValueReference *, size_t, double *);
typedef fmi2Status (*fmi2DoStep_t)(fmi2Component, double, double, fmi2Boolean);
typedef fmi2Status (*fmi2GetFMUstate_t)(fmi2Component, fmi2FMUstate *);
typedef fmi2Status (*fmi2SetFMUstate_t)(fmi2Component, fmi2FMUstate);
typedef fmi2Status (*fmi2FreeFMUstate_t)(fmi2Component, fmi2FMUstate *);
typedef fmi2Status (*fmi2SerializedFMUstateSize_t)(fmi2Component, fmi2FMUstate, size_t *);
typedef fmi2Status (*fmi2SerializeFMUstate_t)(fmi2Component, fmi2FMUstate, char *, size_t);
typedef fmi2Status (*fmi2DeSerializeFMUstate_t)(fmi2Component, const char *, size_t, fmi2FMUstate *);
typedef fmi2Status (*fmi2SetDebugLogging_t)(fmi2Component, fmi2Boolean, size_t, const fmi2String *);

typedef struct {
    const char *library, *guid;
    int cycles, first;
    long ok, discard, error, states, reloads, still_loaded, stale_refused, freed_in_callback, foreign_free_refused;
    int failed;
} Work;

#define FAIL(...) do { fprintf(stderr, __VA_ARGS__); w->failed = 1; return NULL; } while (0)
#undef LOAD
#define LOAD(name) name##_t name = (name##_t)dlsym(lib, #name); if (!name) FAIL("missing %s\n", #name);

static void *worker(void *arg) {
    Work *w = arg;
    Environment env = {NULL, NULL, 0};
    fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, &env};
    const fmi2ValueReference forces[6] = {1, 2, 3, 4, 5, 6};
    const fmi2ValueReference mass = 10;
    const fmi2ValueReference stops = 170; /* Boolean "stops" */
    const fmi2Boolean off = 0;
    const fmi2ValueReference outputs[4] = {102, 115, 121, 133}; /* r[3], angles[1], l[1], E */
    double values[6], out[4];
    void *lib = NULL;

    for (int cycle = w->first; cycle < w->first + w->cycles; cycle++) {
        if ((cycle - w->first) % 100 == 0) { /* load/unload cycles */
            if (lib) { dlclose(lib); w->reloads++; }
            lib = dlopen(w->library, RTLD_NOW | RTLD_LOCAL);
            if (!lib) FAIL("dlopen: %s\n", dlerror());
        }
        LOAD(fmi2Instantiate) LOAD(fmi2FreeInstance) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationMode) LOAD(fmi2Terminate) LOAD(fmi2Reset) LOAD(fmi2SetReal) LOAD(fmi2GetReal)
        LOAD(fmi2DoStep) LOAD(fmi2GetFMUstate) LOAD(fmi2SetFMUstate) LOAD(fmi2FreeFMUstate)
        LOAD(fmi2SerializedFMUstateSize) LOAD(fmi2SerializeFMUstate) LOAD(fmi2DeSerializeFMUstate)
        LOAD(fmi2SetDebugLogging) LOAD(fmi2SetBoolean)

        char name[32];
        snprintf(name, sizeof name, "leak%d", cycle);
        fmi2Component c = fmi2Instantiate(name, 1, w->guid, "file:///tmp", &callbacks, 0, cycle % 7 == 0);
        if (!c) FAIL("instantiate failed\n");
        env.free_instance = fmi2FreeInstance;
        env.component = c;
        fmi2SetDebugLogging(c, cycle % 7 == 0, 0, NULL);
        fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
        fmi2EnterInitializationMode(c);
        if (cycle % 10 == 3) { /* the error path: a bad mass, then reset */
            double m = -1.0;
            fmi2SetReal(c, &mass, 1, &m);
            if (fmi2ExitInitializationMode(c) == 3) w->error++;
            fmi2Reset(c);
            fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
            fmi2EnterInitializationMode(c);
        }
        /* Without end stops a strong pull takes the platform through the base: the discard path. */
        if (cycle % 10 == 5) fmi2SetBoolean(c, &stops, 1, &off);
        fmi2ExitInitializationMode(c);
        if (cycle % 10 == 9) { /* the host frees the instance from its logger during a call */
            env.armed = 1;
            fmi2Status s = fmi2DoStep(c, 123.0, 1e-3, 1); /* wrong communication point: an error message */
            if (s == 3 && !env.armed && fmi2DoStep(c, 0.0, 1e-3, 1) == 3) w->freed_in_callback++;
            fmi2FreeInstance(c); /* freed already: nothing happens */
            continue;
        }
        double t = 0.0;
        for (int i = 0; i < 10; i++) {
            int pull = cycle % 10 == 5 && i == 5; /* pull the platform through the base */
            for (int k = 0; k < 6; k++) values[k] = pull ? -1.0e6 : 5900.715 + k;
            fmi2SetReal(c, forces, 6, values);
            double h = pull ? 0.5 : 1e-3;
            fmi2Status s = fmi2DoStep(c, t, h, 1);
            if (s == 0) { w->ok++; t += h; }
            else if (s == 2) { w->discard++; break; } /* the discard path */
            fmi2GetReal(c, outputs, 4, out);
        }
        /* FMU state: get, serialize, deserialize, set, free. */
        fmi2FMUstate st = NULL, back = NULL;
        if (fmi2GetFMUstate(c, &st) == 0) {
            size_t size = 0;
            fmi2SerializedFMUstateSize(c, st, &size);
            char *bytes = malloc(size);
            fmi2SerializeFMUstate(c, st, bytes, size);
            if (cycle % 10 == 7) bytes[size / 2] ^= 1; /* a corrupted copy is refused */
            if (fmi2DeSerializeFMUstate(c, bytes, size, &back) == 0) {
                fmi2SetFMUstate(c, back);
                fmi2FreeFMUstate(c, &back);
                w->states++;
            }
            fmi2GetFMUstate(c, &st); /* reuse of an existing state */
            fmi2FreeFMUstate(c, &st);
            free(bytes);
        }
        if (cycle % 10 == 8) { /* a state may only be freed by the instance that made it */
            fmi2Component other = fmi2Instantiate("other", 1, w->guid, "file:///tmp", &callbacks, 0, 0);
            fmi2FMUstate mine = NULL;
            fmi2GetFMUstate(c, &mine);
            if (other && fmi2FreeFMUstate(other, &mine) == 3 && mine && fmi2FreeFMUstate(c, &mine) == 0 && !mine)
                w->foreign_free_refused++;
            fmi2FreeInstance(other);
        }
        fmi2Terminate(c);
        fmi2FreeInstance(c);
        fmi2FreeInstance(NULL);
        /* The handle is stale now: refused without touching the freed memory, and freeing it
         * again does nothing. */
        if (fmi2DoStep(c, t, 1e-3, 1) == 3 && fmi2Terminate(c) == 3) w->stale_refused++;
        fmi2FreeInstance(c);
    }
    dlclose(lib);
    /* Alone, the last dlclose must unload the library (with other threads it may still be in use). */
    void *still = dlopen(w->library, RTLD_NOW | RTLD_NOLOAD);
    if (still) { w->still_loaded = 1; dlclose(still); }
    return NULL;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s library guid [cycles] [threads]\n", argv[0]);
        return 2;
    }
    int cycles = argc > 3 ? atoi(argv[3]) : 1000;
    int threads = argc > 4 ? atoi(argv[4]) : 1;
    if (threads < 1 || threads > 64) threads = 1;
    Work work[64];
    pthread_t ids[64];
    for (int i = 0; i < threads; i++) {
        work[i] = (Work){argv[1], argv[2], cycles / threads, i * (cycles / threads), 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
        if (threads == 1) worker(&work[i]);
        else pthread_create(&ids[i], NULL, worker, &work[i]);
    }
    long ok = 0, discard = 0, error = 0, states = 0, reloads = 0, stale = 0, in_callback = 0, foreign = 0;
    int failed = 0;
    for (int i = 0; i < threads; i++) {
        if (threads > 1) pthread_join(ids[i], NULL);
        ok += work[i].ok; discard += work[i].discard; error += work[i].error; states += work[i].states;
        reloads += work[i].reloads; failed |= work[i].failed; stale += work[i].stale_refused;
        in_callback += work[i].freed_in_callback; foreign += work[i].foreign_free_refused;
    }
    void *still = dlopen(argv[1], RTLD_NOW | RTLD_NOLOAD);
    if (still) dlclose(still);
    printf("cycles %d in %d threads: steps ok %ld, discarded %ld, refused parameter sets %ld, state round trips %ld, "
           "reloads %ld, log messages %lu, library unloaded at the end: %s\n"
           "stale handles refused %ld, freed from the logger during a call %ld, states freed by another instance "
           "refused %ld\n", cycles, threads, ok, discard, error, states, reloads, messages, still ? "no" : "yes", stale,
           in_callback, foreign);
    return failed ? 1 : (still ? 3 : 0);
}
