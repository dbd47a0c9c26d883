/* A small FMI 2.0 / 3.0 host in portable C, built for every platform the FMUs carry
 * (Linux x86-64 with gcc, Windows x64 with mingw-w64, Linux aarch64 with the aarch64 gcc)
 * and run there (natively, under wine, under qemu-user) by tests/python/test_platforms.py,
 * which compares what each platform prints with the Linux x86-64 run, bit for bit.
 *
 *   platform_host VERSION PLATFORM_BINARY CONTROLLER_BINARY RESOURCE_URI < script
 *
 * VERSION is 2 or 3. The binaries are the unpacked FMUs' (any characters in their paths:
 * UTF-8 on Linux, UTF-16 on Windows). The script on standard input declares the variables
 * (from the model descriptions), then runs commands, one per line:
 *
 *   token MODEL TOKEN                        MODEL is platform or controller
 *   states MODEL N INDICATORS                continuous states and event indicators (FMI 2 ME;
 *                                            FMI 3 asks the instance)
 *   var MODEL NAME TYPE COUNT VR...          TYPE R (Real/Float64), I (Integer/Int32), B (Boolean);
 *                                            FMI 2: COUNT value references; FMI 3: one and COUNT
 *   new NAME MODEL cs|me                     instantiate (every message it logs is printed)
 *   debug NAME CATEGORY                      switch that debug log category on (logEvents, ...)
 *   set NAME VAR VALUE...
 *   init NAME                                start time 0, no stop time; ME: event iteration
 *   step NAME H N                            N communication steps of H (Co-Simulation)
 *   euler NAME H N                           N explicit Euler steps of H (Model Exchange)
 *   loop PLATFORM CONTROLLER H N             the closed loop, Gauss-Seidel
 *   print NAME VAR...                        the values' bits in hex
 *   save|restore|release NAME SLOT           FMU state get / set / free (the host's clock with it)
 *   serialize NAME SLOT                      its bytes: size and FNV-1a hash printed
 *   deserialize NAME SLOT                    those bytes (of any instance of the model) into a new
 *                                            FMU state of this one, then set
 *   dirder NAME UNKNOWN KNOWN                d UNKNOWN / d KNOWN[1], the bits printed
 *   badtoken MODEL                           instantiate with a foreign token
 *   badstep NAME                             a negative communication step
 *   free NAME
 *
 * Every line it prints is deterministic (no addresses, no times), so outputs compare as text.
 */
#include <inttypes.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <fcntl.h>
#include <io.h>
#include <windows.h>
typedef HMODULE Library;
static Library open_library(const char *utf8) {
    wchar_t wide[4096];
    if (!MultiByteToWideChar(CP_UTF8, 0, utf8, -1, wide, 4096)) return NULL;
    Library l = LoadLibraryW(wide);
    if (!l) fprintf(stdout, "error LoadLibraryW failed: %lu\n", (unsigned long)GetLastError());
    return l;
}
static void *library_symbol(Library l, const char *name) { return (void *)GetProcAddress(l, name); }
static void close_library(Library l) { FreeLibrary(l); }
#else
#include <dlfcn.h>
typedef void *Library;
static Library open_library(const char *path) {
    Library l = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!l) fprintf(stdout, "error dlopen failed: %s\n", dlerror());
    return l;
}
static void *library_symbol(Library l, const char *name) { return dlsym(l, name); }
static void close_library(Library l) { dlclose(l); }
#endif

/* ---- FMI types (fmi2TypesPlatform.h, fmi3PlatformTypes.h) ---- */
typedef void *Instance;
typedef void *State;
typedef int fmi2Status;
typedef int fmi2Boolean;
typedef void (*fmi2Logger)(void *, const char *, int, const char *, const char *, ...);
typedef struct {
    fmi2Logger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(void *, int);
    void *componentEnvironment;
} fmi2Callbacks;
typedef void (*fmi3Logger)(void *, int, const char *, const char *);

/* The functions used, by name, from each library. */
#define FUNCTIONS(X)                                                                           \
    X(fmi2Instantiate) X(fmi2FreeInstance) X(fmi2SetDebugLogging) X(fmi3SetDebugLogging) X(fmi2SetupExperiment) X(fmi2EnterInitializationMode) \
    X(fmi2ExitInitializationMode) X(fmi2GetReal) X(fmi2SetReal) X(fmi2SetInteger)             \
    X(fmi2SetBoolean) X(fmi2DoStep) X(fmi2GetFMUstate) X(fmi2SetFMUstate) X(fmi2FreeFMUstate) \
    X(fmi2SerializedFMUstateSize) X(fmi2SerializeFMUstate) X(fmi2DeSerializeFMUstate)         \
    X(fmi2GetDirectionalDerivative) X(fmi2NewDiscreteStates) X(fmi2EnterContinuousTimeMode)   \
    X(fmi2EnterEventMode) X(fmi2CompletedIntegratorStep) X(fmi2SetTime)                       \
    X(fmi2SetContinuousStates) X(fmi2GetContinuousStates) X(fmi2GetDerivatives)                \
    X(fmi2GetEventIndicators) X(fmi3InstantiateCoSimulation) X(fmi3InstantiateModelExchange)  \
    X(fmi3FreeInstance) X(fmi3EnterInitializationMode) X(fmi3ExitInitializationMode)          \
    X(fmi3GetFloat64) X(fmi3SetFloat64) X(fmi3SetInt32) X(fmi3SetBoolean) X(fmi3DoStep)        \
    X(fmi3GetFMUState) X(fmi3SetFMUState) X(fmi3FreeFMUState) X(fmi3SerializedFMUStateSize)   \
    X(fmi3SerializeFMUState) X(fmi3DeserializeFMUState) X(fmi3GetDirectionalDerivative)       \
    X(fmi3UpdateDiscreteStates) X(fmi3EnterContinuousTimeMode) X(fmi3EnterEventMode)          \
    X(fmi3CompletedIntegratorStep) X(fmi3SetTime) X(fmi3SetContinuousStates)                  \
    X(fmi3GetContinuousStates) X(fmi3GetContinuousStateDerivatives)                            \
    X(fmi3GetNumberOfContinuousStates) X(fmi3GetNumberOfEventIndicators) X(fmi3GetEventIndicators)

typedef struct {
    Library library;
#define FIELD(name) void *name;
    FUNCTIONS(FIELD)
#undef FIELD
} Api;

/* Calls through a function pointer of the given signature. */
#define CALL(api, name, type, ...) (((type)(api)->name)(__VA_ARGS__))

typedef int (*i_c)(Instance);
typedef void (*v_c)(Instance);

/* ---- the variables and instances ---- */
#define MAX_VARS 512
#define MAX_INSTANCES 8
#define MAX_SLOTS 4
#define MAX_STATES 128
#define MAX_VALUES 32 /* values of one variable (an array) */

typedef struct {
    int model; /* 0 platform, 1 controller */
    char name[64];
    char type;
    int count;
    unsigned int vr[MAX_VALUES];
} Variable;

typedef struct {
    char name[32];
    int model, exchange; /* exchange: Model Exchange */
    Instance instance;
    double time;
    State slots[MAX_SLOTS];
    unsigned char *bytes[MAX_SLOTS];
    size_t sizes[MAX_SLOTS];
    double saved_time[MAX_SLOTS]; /* the host's clock when the state was saved */
} Slave;

static int version;
static Api apis[2];
static char tokens[2][128];
static int n_states[2], n_indicators[2];
static Variable vars[MAX_VARS];
static int n_vars;
static Slave slaves[MAX_INSTANCES];
static const char *resource_uri;
static const char *model_names[2] = {"platform", "controller"};

static int model_of(const char *name) {
    if (!strcmp(name, "platform")) return 0;
    if (!strcmp(name, "controller")) return 1;
    fprintf(stdout, "error unknown model %s\n", name);
    exit(2);
}

static Slave *slave(const char *name) {
    for (int i = 0; i < MAX_INSTANCES; i++)
        if (slaves[i].instance && !strcmp(slaves[i].name, name)) return &slaves[i];
    fprintf(stdout, "error no instance %s\n", name);
    exit(2);
}

static Variable *var(int model, const char *name) {
    for (int i = 0; i < n_vars; i++)
        if (vars[i].model == model && !strcmp(vars[i].name, name)) return &vars[i];
    fprintf(stdout, "error no variable %s in %s\n", name, model_names[model]);
    exit(2);
}

/* ---- logging: every message printed on one line, line breaks made visible ---- */
static void print_message(const char *instance, int status, const char *category, const char *message) {
    fprintf(stdout, "log %s %d %s ", instance ? instance : "(null)", status, category ? category : "(null)");
    for (const char *c = message; *c; c++) {
        if (*c == '\n') fputs("\\n", stdout);
        else if (*c == '\r') fputs("\\r", stdout);
        else fputc(*c, stdout);
    }
    fputc('\n', stdout);
}

static void logger2(void *env, const char *instance, int status, const char *category, const char *message, ...) {
    char buffer[8192];
    va_list args;
    va_start(args, message);
    vsnprintf(buffer, sizeof buffer, message, args); /* as FMPy and FMI Library do */
    va_end(args);
    (void)env;
    print_message(instance, status, category, buffer);
}

static void logger3(void *env, int status, const char *category, const char *message) {
    print_message(((Slave *)env)->name, status, category, message);
}

static fmi2Callbacks callbacks2 = {logger2, calloc, free, NULL, NULL};

static void check(int status, const char *what, const Slave *s) {
    if (status != 0) fprintf(stdout, "status %s %s %d\n", s ? s->name : "-", what, status);
}

/* ---- values ---- */
static int get_reals(Slave *s, Variable *v, double *out) {
    Api *a = &apis[s->model];
    if (version == 2)
        return CALL(a, fmi2GetReal, int (*)(Instance, const unsigned *, size_t, double *), s->instance, v->vr,
                    (size_t)v->count, out);
    return CALL(a, fmi3GetFloat64, int (*)(Instance, const unsigned *, size_t, double *, size_t), s->instance, v->vr,
                (size_t)1, out, (size_t)v->count);
}

static int set_values(Slave *s, Variable *v, const double *values) {
    Api *a = &apis[s->model];
    size_t nvr = version == 2 ? (size_t)v->count : 1;
    if (v->type == 'R') {
        if (version == 2)
            return CALL(a, fmi2SetReal, int (*)(Instance, const unsigned *, size_t, const double *), s->instance,
                        v->vr, nvr, values);
        return CALL(a, fmi3SetFloat64, int (*)(Instance, const unsigned *, size_t, const double *, size_t),
                    s->instance, v->vr, nvr, values, (size_t)v->count);
    }
    if (v->type == 'I') {
        int ints[MAX_VALUES];
        for (int i = 0; i < v->count; i++) ints[i] = (int)values[i];
        if (version == 2)
            return CALL(a, fmi2SetInteger, int (*)(Instance, const unsigned *, size_t, const int *), s->instance,
                        v->vr, nvr, ints);
        return CALL(a, fmi3SetInt32, int (*)(Instance, const unsigned *, size_t, const int *, size_t), s->instance,
                    v->vr, nvr, ints, (size_t)v->count);
    }
    if (version == 2) {
        int bools[MAX_VALUES];
        for (int i = 0; i < v->count; i++) bools[i] = values[i] != 0.0;
        return CALL(a, fmi2SetBoolean, int (*)(Instance, const unsigned *, size_t, const int *), s->instance, v->vr,
                    nvr, bools);
    }
    unsigned char bools[MAX_VALUES]; /* fmi3Boolean is C's bool */
    for (int i = 0; i < v->count; i++) bools[i] = values[i] != 0.0;
    return CALL(a, fmi3SetBoolean, int (*)(Instance, const unsigned *, size_t, const unsigned char *, size_t),
                s->instance, v->vr, nvr, bools, (size_t)v->count);
}

static void print_bits(const char *label, const double *x, int n) {
    fprintf(stdout, "%s", label);
    for (int i = 0; i < n; i++) {
        uint64_t bits;
        memcpy(&bits, &x[i], sizeof bits);
        fprintf(stdout, " %016" PRIx64, bits);
    }
    fputc('\n', stdout);
}

/* ---- life cycle ---- */
static Instance instantiate(Slave *s, const char *token) {
    Api *a = &apis[s->model];
    if (version == 2)
        return CALL(a, fmi2Instantiate, Instance (*)(const char *, int, const char *, const char *, const fmi2Callbacks *, int, int),
                    s->name, s->exchange ? 0 : 1, token, resource_uri, &callbacks2, 0, 0);
    if (s->exchange)
        return CALL(a, fmi3InstantiateModelExchange,
                    Instance (*)(const char *, const char *, const char *, unsigned char, unsigned char, void *, fmi3Logger),
                    s->name, token, resource_uri, 0, 0, s, logger3);
    return CALL(a, fmi3InstantiateCoSimulation,
                Instance (*)(const char *, const char *, const char *, unsigned char, unsigned char, unsigned char,
                             unsigned char, const unsigned *, size_t, void *, fmi3Logger, void *),
                s->name, token, resource_uri, 0, 0, 0, 0, NULL, (size_t)0, s, logger3, NULL);
}

/* Event iteration of Model Exchange, then continuous-time mode. */
static void settle_events(Slave *s) {
    Api *a = &apis[s->model];
    for (int i = 0; i < 100; i++) {
        int more = 0;
        if (version == 2) {
            struct { int newDiscreteStatesNeeded, terminateSimulation, nominalsChanged, valuesChanged, nextEventTimeDefined; double nextEventTime; } info;
            check(CALL(a, fmi2NewDiscreteStates, int (*)(Instance, void *), s->instance, &info), "newDiscreteStates", s);
            more = info.newDiscreteStatesNeeded;
        } else {
            unsigned char need, terminate, nominals, values, defined;
            double next;
            check(CALL(a, fmi3UpdateDiscreteStates,
                       int (*)(Instance, unsigned char *, unsigned char *, unsigned char *, unsigned char *, unsigned char *, double *),
                       s->instance, &need, &terminate, &nominals, &values, &defined, &next),
                  "updateDiscreteStates", s);
            more = need;
        }
        if (!more) break;
    }
    if (version == 2) check(CALL(a, fmi2EnterContinuousTimeMode, i_c, s->instance), "enterContinuousTimeMode", s);
    else check(CALL(a, fmi3EnterContinuousTimeMode, i_c, s->instance), "enterContinuousTimeMode", s);
}

static void init(Slave *s) {
    Api *a = &apis[s->model];
    if (version == 2) {
        check(CALL(a, fmi2ExitInitializationMode, i_c, s->instance), "exitInitializationMode", s);
    } else {
        check(CALL(a, fmi3ExitInitializationMode, i_c, s->instance), "exitInitializationMode", s);
    }
    if (s->exchange) {
        settle_events(s);
        if (version == 3) {
            /* FMI 3 tells the sizes (its model description counts array variables, not values). */
            size_t n = 0, m = 0;
            check(CALL(a, fmi3GetNumberOfContinuousStates, int (*)(Instance, size_t *), s->instance, &n), "getNumberOfContinuousStates", s);
            check(CALL(a, fmi3GetNumberOfEventIndicators, int (*)(Instance, size_t *), s->instance, &m), "getNumberOfEventIndicators", s);
            if (n > MAX_STATES || m > MAX_STATES) {
                fprintf(stdout, "error %zu states, %zu event indicators: more than %d\n", n, m, MAX_STATES);
                exit(2);
            }
            n_states[s->model] = (int)n;
            n_indicators[s->model] = (int)m;
        }
    }
}

static void enter_init(Slave *s) {
    Api *a = &apis[s->model];
    if (version == 2) {
        check(CALL(a, fmi2SetupExperiment, int (*)(Instance, int, double, double, int, double), s->instance, 0, 0.0, 0.0, 0, 0.0),
              "setupExperiment", s);
        check(CALL(a, fmi2EnterInitializationMode, i_c, s->instance), "enterInitializationMode", s);
    } else {
        check(CALL(a, fmi3EnterInitializationMode, int (*)(Instance, unsigned char, double, double, unsigned char, double),
                   s->instance, 0, 0.0, 0.0, 0, 0.0),
              "enterInitializationMode", s);
    }
}

static int do_step(Slave *s, double h) {
    Api *a = &apis[s->model];
    int status;
    if (version == 2) {
        /* noSetFMUStatePriorToCurrentPoint false: the scripts restore earlier states. */
        status = CALL(a, fmi2DoStep, int (*)(Instance, double, double, int), s->instance, s->time, h, 0);
    } else {
        unsigned char event, terminate, early;
        double last;
        status = CALL(a, fmi3DoStep,
                      int (*)(Instance, double, double, unsigned char, unsigned char *, unsigned char *, unsigned char *, double *),
                      s->instance, s->time, h, 0, &event, &terminate, &early, &last);
    }
    if (status <= 1) s->time += h;
    return status;
}

/* One explicit Euler step of Model Exchange, with the event handling a host must do. */
static void euler_step(Slave *s, double h) {
    Api *a = &apis[s->model];
    double x[MAX_STATES], dx[MAX_STATES];
    int n = n_states[s->model];
    unsigned char enter = 0, terminate = 0;
    if (version == 2) {
        check(CALL(a, fmi2GetContinuousStates, int (*)(Instance, double *, size_t), s->instance, x, (size_t)n), "getContinuousStates", s);
        check(CALL(a, fmi2GetDerivatives, int (*)(Instance, double *, size_t), s->instance, dx, (size_t)n), "getDerivatives", s);
    } else {
        check(CALL(a, fmi3GetContinuousStates, int (*)(Instance, double *, size_t), s->instance, x, (size_t)n), "getContinuousStates", s);
        check(CALL(a, fmi3GetContinuousStateDerivatives, int (*)(Instance, double *, size_t), s->instance, dx, (size_t)n),
              "getContinuousStateDerivatives", s);
    }
    for (int i = 0; i < n; i++) x[i] += h * dx[i];
    s->time += h;
    if (version == 2) {
        int enter2 = 0, terminate2 = 0;
        check(CALL(a, fmi2SetTime, int (*)(Instance, double), s->instance, s->time), "setTime", s);
        check(CALL(a, fmi2SetContinuousStates, int (*)(Instance, const double *, size_t), s->instance, x, (size_t)n), "setContinuousStates", s);
        check(CALL(a, fmi2CompletedIntegratorStep, int (*)(Instance, int, int *, int *), s->instance, 0, &enter2, &terminate2),
              "completedIntegratorStep", s);
        enter = (unsigned char)enter2;
    } else {
        check(CALL(a, fmi3SetTime, int (*)(Instance, double), s->instance, s->time), "setTime", s);
        check(CALL(a, fmi3SetContinuousStates, int (*)(Instance, const double *, size_t), s->instance, x, (size_t)n), "setContinuousStates", s);
        check(CALL(a, fmi3CompletedIntegratorStep, int (*)(Instance, unsigned char, unsigned char *, unsigned char *), s->instance, 0,
                   &enter, &terminate),
              "completedIntegratorStep", s);
    }
    if (enter) {
        fprintf(stdout, "event %s\n", s->name);
        if (version == 2) check(CALL(a, fmi2EnterEventMode, i_c, s->instance), "enterEventMode", s);
        else check(CALL(a, fmi3EnterEventMode, i_c, s->instance), "enterEventMode", s);
        settle_events(s);
    }
}

static void print_continuous(Slave *s) {
    Api *a = &apis[s->model];
    double x[MAX_STATES], dx[MAX_STATES], z[MAX_STATES];
    int n = n_states[s->model], m = n_indicators[s->model];
    if (version == 2) {
        check(CALL(a, fmi2GetContinuousStates, int (*)(Instance, double *, size_t), s->instance, x, (size_t)n), "getContinuousStates", s);
        check(CALL(a, fmi2GetDerivatives, int (*)(Instance, double *, size_t), s->instance, dx, (size_t)n), "getDerivatives", s);
        check(CALL(a, fmi2GetEventIndicators, int (*)(Instance, double *, size_t), s->instance, z, (size_t)m), "getEventIndicators", s);
    } else {
        check(CALL(a, fmi3GetContinuousStates, int (*)(Instance, double *, size_t), s->instance, x, (size_t)n), "getContinuousStates", s);
        check(CALL(a, fmi3GetContinuousStateDerivatives, int (*)(Instance, double *, size_t), s->instance, dx, (size_t)n),
              "getContinuousStateDerivatives", s);
        check(CALL(a, fmi3GetEventIndicators, int (*)(Instance, double *, size_t), s->instance, z, (size_t)m), "getEventIndicators", s);
    }
    char label[256];
    snprintf(label, sizeof label, "%s states", s->name);
    print_bits(label, x, n);
    snprintf(label, sizeof label, "%s derivatives", s->name);
    print_bits(label, dx, n);
    snprintf(label, sizeof label, "%s indicators", s->name);
    print_bits(label, z, m);
}

/* FNV-1a, 64 bits: the serialized state's fingerprint. */
static uint64_t fnv1a(const unsigned char *bytes, size_t n) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (size_t i = 0; i < n; i++) h = (h ^ bytes[i]) * 0x100000001b3ULL;
    return h;
}

static int load(Api *api, const char *path) {
    api->library = open_library(path);
    if (!api->library) return 0;
#define RESOLVE(name)                                                     \
    api->name = library_symbol(api->library, #name);                     \
    if (!api->name) {                                                    \
        fprintf(stdout, "error %s does not export %s\n", path, #name);   \
        return 0;                                                        \
    }
    FUNCTIONS(RESOLVE)
#undef RESOLVE
    return 1;
}

/* A state slot's number, 0 to MAX_SLOTS - 1. */
static int slot(const char *word) {
    int k = word ? atoi(word) : -1;
    if (k < 0 || k >= MAX_SLOTS) {
        fprintf(stdout, "error slot %s: 0 to %d\n", word ? word : "(none)", MAX_SLOTS - 1);
        exit(2);
    }
    return k;
}

static char *next_word(char **cursor) {
    char *s = *cursor;
    while (*s == ' ' || *s == '\t') s++;
    if (!*s || *s == '\n' || *s == '\r') return NULL;
    char *w = s;
    while (*s && *s != ' ' && *s != '\t' && *s != '\n' && *s != '\r') s++;
    if (*s) *s++ = 0;
    *cursor = s;
    return w;
}


static void free_slave(Slave *s) {
    Api *a = &apis[s->model];
    for (int k = 0; k < MAX_SLOTS; k++) {
        if (s->slots[k]) {
            if (version == 2) CALL(a, fmi2FreeFMUstate, int (*)(Instance, State *), s->instance, &s->slots[k]);
            else CALL(a, fmi3FreeFMUState, int (*)(Instance, State *), s->instance, &s->slots[k]);
        }
        free(s->bytes[k]);
        s->bytes[k] = NULL;
    }
    if (version == 2) CALL(a, fmi2FreeInstance, v_c, s->instance);
    else CALL(a, fmi3FreeInstance, v_c, s->instance);
    memset(s, 0, sizeof *s);
}

static int run(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: platform_host 2|3 PLATFORM_BINARY CONTROLLER_BINARY RESOURCE_URI < script\n");
        return 2;
    }
    version = atoi(argv[1]);
    resource_uri = argv[4];
    if (!load(&apis[0], argv[2]) || !load(&apis[1], argv[3])) return 1;
    char line[4096];
    while (fgets(line, sizeof line, stdin)) {
        char *cursor = line;
        char *command = next_word(&cursor);
        if (!command || command[0] == '#') continue;
        if (!strcmp(command, "token")) {
            int m = model_of(next_word(&cursor));
            snprintf(tokens[m], sizeof tokens[m], "%s", next_word(&cursor));
        } else if (!strcmp(command, "states")) {
            int m = model_of(next_word(&cursor));
            n_states[m] = atoi(next_word(&cursor));
            n_indicators[m] = atoi(next_word(&cursor));
            if (n_states[m] < 0 || n_states[m] > MAX_STATES || n_indicators[m] < 0 || n_indicators[m] > MAX_STATES) {
                fprintf(stdout, "error %d states, %d event indicators: 0 to %d here\n", n_states[m], n_indicators[m], MAX_STATES);
                return 2;
            }
        } else if (!strcmp(command, "var")) {
            if (n_vars == MAX_VARS) {
                fprintf(stdout, "error more than %d variables\n", MAX_VARS);
                return 2;
            }
            Variable *v = &vars[n_vars++];
            v->model = model_of(next_word(&cursor));
            snprintf(v->name, sizeof v->name, "%s", next_word(&cursor));
            v->type = next_word(&cursor)[0];
            v->count = atoi(next_word(&cursor));
            if (v->count < 1 || v->count > MAX_VALUES) {
                fprintf(stdout, "error %s has %d values (1 to %d here)\n", v->name, v->count, MAX_VALUES);
                return 2;
            }
            int nvr = version == 2 ? v->count : 1;
            for (int i = 0; i < nvr; i++) v->vr[i] = (unsigned)strtoul(next_word(&cursor), NULL, 10);
        } else if (!strcmp(command, "new")) {
            Slave *s = NULL;
            for (int i = 0; i < MAX_INSTANCES && !s; i++)
                if (!slaves[i].instance) s = &slaves[i];
            if (!s) {
                fprintf(stdout, "error more than %d instances\n", MAX_INSTANCES);
                return 2;
            }
            snprintf(s->name, sizeof s->name, "%s", next_word(&cursor));
            s->model = model_of(next_word(&cursor));
            s->exchange = !strcmp(next_word(&cursor), "me");
            s->instance = instantiate(s, tokens[s->model]);
            fprintf(stdout, "new %s %s\n", s->name, s->instance ? "ok" : "NULL");
            if (!s->instance) return 1;
            enter_init(s);
        } else if (!strcmp(command, "set")) {
            Slave *s = slave(next_word(&cursor));
            Variable *v = var(s->model, next_word(&cursor));
            double values[MAX_VALUES];
            for (int i = 0; i < v->count; i++) values[i] = strtod(next_word(&cursor), NULL);
            check(set_values(s, v, values), "set", s);
        } else if (!strcmp(command, "debug")) {
            Slave *s = slave(next_word(&cursor));
            const char *category = next_word(&cursor);
            Api *a = &apis[s->model];
            if (version == 2)
                check(CALL(a, fmi2SetDebugLogging, int (*)(Instance, int, size_t, const char *const *), s->instance, 1, (size_t)1, &category),
                      "setDebugLogging", s);
            else
                check(CALL(a, fmi3SetDebugLogging, int (*)(Instance, unsigned char, size_t, const char *const *), s->instance, 1, (size_t)1, &category),
                      "setDebugLogging", s);
        } else if (!strcmp(command, "init")) {
            init(slave(next_word(&cursor)));
        } else if (!strcmp(command, "step")) {
            Slave *s = slave(next_word(&cursor));
            double h = strtod(next_word(&cursor), NULL);
            int n = atoi(next_word(&cursor));
            for (int i = 0; i < n; i++) {
                int status = do_step(s, h);
                if (status > 1) {
                    fprintf(stdout, "status %s doStep %d at step %d\n", s->name, status, i);
                    break;
                }
            }
        } else if (!strcmp(command, "euler")) {
            Slave *s = slave(next_word(&cursor));
            double h = strtod(next_word(&cursor), NULL);
            int n = atoi(next_word(&cursor));
            for (int i = 0; i < n; i++) euler_step(s, h);
            print_continuous(s);
        } else if (!strcmp(command, "loop")) {
            Slave *p = slave(next_word(&cursor)), *c = slave(next_word(&cursor));
            double h = strtod(next_word(&cursor), NULL);
            int n = atoi(next_word(&cursor));
            Variable *l = var(0, "l"), *ldot = var(0, "ldot"), *F = var(0, "F");
            Variable *cl = var(1, "l"), *cldot = var(1, "ldot"), *cF = var(1, "F");
            for (int i = 0; i < n; i++) {
                double x[MAX_VALUES];
                check(get_reals(p, l, x), "get l", p);
                check(set_values(c, cl, x), "set l", c);
                check(get_reals(p, ldot, x), "get ldot", p);
                check(set_values(c, cldot, x), "set ldot", c);
                check(get_reals(c, cF, x), "get F", c);
                check(set_values(p, F, x), "set F", p);
                int status = do_step(p, h);
                if (status > 1 || do_step(c, h) > 1) {
                    fprintf(stdout, "status loop stopped at step %d\n", i);
                    break;
                }
            }
        } else if (!strcmp(command, "print")) {
            Slave *s = slave(next_word(&cursor));
            char *name;
            while ((name = next_word(&cursor))) {
                Variable *v = var(s->model, name);
                double x[MAX_VALUES] = {0};
                if (v->type != 'R') {
                    fprintf(stdout, "error print reads Real/Float64 variables only, not %s\n", name);
                    return 2;
                }
                check(get_reals(s, v, x), "get", s);
                char label[256];
                snprintf(label, sizeof label, "%s %s", s->name, name);
                print_bits(label, x, v->count);
            }
        } else if (!strcmp(command, "save") || !strcmp(command, "restore") || !strcmp(command, "release")) {
            Slave *s = slave(next_word(&cursor));
            int k = slot(next_word(&cursor));
            Api *a = &apis[s->model];
            int status;
            if (command[0] == 's')
                status = version == 2 ? CALL(a, fmi2GetFMUstate, int (*)(Instance, State *), s->instance, &s->slots[k])
                                      : CALL(a, fmi3GetFMUState, int (*)(Instance, State *), s->instance, &s->slots[k]);
            else if (command[0] == 'r' && command[2] == 's')
                status = version == 2 ? CALL(a, fmi2SetFMUstate, int (*)(Instance, State), s->instance, s->slots[k])
                                      : CALL(a, fmi3SetFMUState, int (*)(Instance, State), s->instance, s->slots[k]);
            else
                status = version == 2 ? CALL(a, fmi2FreeFMUstate, int (*)(Instance, State *), s->instance, &s->slots[k])
                                      : CALL(a, fmi3FreeFMUState, int (*)(Instance, State *), s->instance, &s->slots[k]);
            check(status, command, s);
            /* The host's clock goes with the state: the next communication point is the one
             * the FMU's time was saved at, bit for bit. */
            if (command[0] == 's') s->saved_time[k] = s->time;
            else if (command[2] == 's') s->time = s->saved_time[k];
            fprintf(stdout, "%s %s %d\n", command, s->name, status);
        } else if (!strcmp(command, "serialize")) {
            Slave *s = slave(next_word(&cursor));
            int k = slot(next_word(&cursor));
            Api *a = &apis[s->model];
            size_t size = 0;
            if (version == 2)
                check(CALL(a, fmi2SerializedFMUstateSize, int (*)(Instance, State, size_t *), s->instance, s->slots[k], &size), "size", s);
            else
                check(CALL(a, fmi3SerializedFMUStateSize, int (*)(Instance, State, size_t *), s->instance, s->slots[k], &size), "size", s);
            free(s->bytes[k]);
            s->bytes[k] = malloc(size);
            s->sizes[k] = size;
            if (version == 2)
                check(CALL(a, fmi2SerializeFMUstate, int (*)(Instance, State, unsigned char *, size_t), s->instance, s->slots[k], s->bytes[k], size),
                      "serialize", s);
            else
                check(CALL(a, fmi3SerializeFMUState, int (*)(Instance, State, unsigned char *, size_t), s->instance, s->slots[k], s->bytes[k], size),
                      "serialize", s);
            fprintf(stdout, "serialized %s %zu bytes fnv1a %016" PRIx64 "\n", s->name, size, fnv1a(s->bytes[k], size));
        } else if (!strcmp(command, "deserialize")) {
            /* The bytes of slot K (from any instance of the same model) into this one's slot K. */
            Slave *s = slave(next_word(&cursor));
            int k = slot(next_word(&cursor));
            Slave *from = NULL;
            for (int i = 0; i < MAX_INSTANCES; i++)
                if (slaves[i].instance && slaves[i].bytes[k] && slaves[i].model == s->model) from = &slaves[i];
            if (!from) {
                fprintf(stdout, "error no serialized state in slot %d for %s\n", k, s->name);
                return 2;
            }
            Api *a = &apis[s->model];
            State state = NULL;
            int status = version == 2
                ? CALL(a, fmi2DeSerializeFMUstate, int (*)(Instance, const unsigned char *, size_t, State *), s->instance, from->bytes[k], from->sizes[k], &state)
                : CALL(a, fmi3DeserializeFMUState, int (*)(Instance, const unsigned char *, size_t, State *), s->instance, from->bytes[k], from->sizes[k], &state);
            check(status, "deserialize", s);
            status = version == 2 ? CALL(a, fmi2SetFMUstate, int (*)(Instance, State), s->instance, state)
                                  : CALL(a, fmi3SetFMUState, int (*)(Instance, State), s->instance, state);
            check(status, "set deserialized", s);
            if (version == 2) CALL(a, fmi2FreeFMUstate, int (*)(Instance, State *), s->instance, &state);
            else CALL(a, fmi3FreeFMUState, int (*)(Instance, State *), s->instance, &state);
            s->time = from->saved_time[k];
            fprintf(stdout, "deserialized %s %d\n", s->name, status);
        } else if (!strcmp(command, "dirder")) {
            Slave *s = slave(next_word(&cursor));
            Variable *unknown = var(s->model, next_word(&cursor));
            Variable *known = var(s->model, next_word(&cursor));
            Api *a = &apis[s->model];
            double seed = 1.0, sensitivity[MAX_VALUES];
            int status;
            if (version == 2)
                status = CALL(a, fmi2GetDirectionalDerivative,
                              int (*)(Instance, const unsigned *, size_t, const unsigned *, size_t, const double *, double *),
                              s->instance, unknown->vr, (size_t)unknown->count, known->vr, (size_t)1, &seed, sensitivity);
            else {
                /* The first element of an FMI 3 array is its own known: seed the whole array, first 1. */
                double seeds[MAX_VALUES] = {1.0};
                status = CALL(a, fmi3GetDirectionalDerivative,
                              int (*)(Instance, const unsigned *, size_t, const unsigned *, size_t, const double *, size_t, double *, size_t),
                              s->instance, unknown->vr, (size_t)1, known->vr, (size_t)1, seeds, (size_t)known->count,
                              sensitivity, (size_t)unknown->count);
            }
            check(status, "getDirectionalDerivative", s);
            char label[256];
            snprintf(label, sizeof label, "%s d%s/d%s", s->name, unknown->name, known->name);
            print_bits(label, sensitivity, unknown->count);
        } else if (!strcmp(command, "badtoken")) {
            Slave probe;
            memset(&probe, 0, sizeof probe);
            snprintf(probe.name, sizeof probe.name, "intruder");
            probe.model = model_of(next_word(&cursor));
            probe.instance = instantiate(&probe, "{00000000-0000-0000-0000-000000000000}");
            fprintf(stdout, "badtoken %s\n", probe.instance ? "ACCEPTED" : "refused");
            if (probe.instance) free_slave(&probe);
        } else if (!strcmp(command, "badstep")) {
            Slave *s = slave(next_word(&cursor));
            double t = s->time;
            int status = do_step(s, -1e-3);
            s->time = t;
            fprintf(stdout, "badstep %s %d\n", s->name, status);
        } else if (!strcmp(command, "free")) {
            free_slave(slave(next_word(&cursor)));
        } else {
            fprintf(stdout, "error unknown command %s\n", command);
            return 2;
        }
        fflush(stdout);
    }
    for (int i = 0; i < MAX_INSTANCES; i++)
        if (slaves[i].instance) free_slave(&slaves[i]);
    close_library(apis[1].library);
    close_library(apis[0].library);
    fprintf(stdout, "done\n");
    return 0;
}

#ifdef _WIN32
/* The paths as UTF-16 from Windows, to UTF-8 for the rest; binary stdout (no \r added). */
int wmain(int argc, wchar_t **wargv) {
    static char storage[8][4096];
    char *argv[8];
    if (argc > 8) argc = 8;
    for (int i = 0; i < argc; i++) {
        WideCharToMultiByte(CP_UTF8, 0, wargv[i], -1, storage[i], sizeof storage[i], NULL, NULL);
        argv[i] = storage[i];
    }
    _setmode(_fileno(stdout), _O_BINARY);
    return run(argc, argv);
}
#else
int main(int argc, char **argv) { return run(argc, argv); }
#endif
