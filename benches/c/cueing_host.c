/* A plain FMI 2.0 Co-Simulation host for the cueing FMU's real-time measurements
 * (benches/cueing_bench.py, tests/python/test_cueing_realtime.py): it loads the binary with
 * dlopen, sets cueing.method, and drives the FMU through recorded drives at 1 kHz: per step
 * it sets f and omega, calls fmi2DoStep of 1 ms and reads the pose command (18 Reals).
 *
 *   cueing_host SO GUID RESOURCES METHOD MODE DRIVE...
 *
 * A DRIVE is a file of doubles, six per millisecond (f[1..3], omega[1..3]). MODE:
 *   time           per step the wall time of the set-step-get cycle (CLOCK_MONOTONIC around
 *                  it), and mpc.iterations after the step; prints per drive the steps, the
 *                  mean and largest cycle, the largest cycle with a solve and without, and the
 *                  steps with the most iterations (for `count`).
 *   count:I,J,...  under callgrind (--collect-atstart=no): collects only the cycles of steps
 *                  I, J, ... of each drive and dumps after each (their instructions); steps
 *                  given as drive:step pairs, e.g. count:0:1230,3:57.
 *   all            under callgrind: collects every cycle of every drive (the mean).
 *   quiet:W:N      for counting allocations and system calls: the first drive's first W
 *                  steps run, then the marker getppid() (a system call the host makes
 *                  nowhere else), then N steps, then getppid() again. An
 *                  LD_PRELOAD counter (cueing_alloc.c) counts allocations between
 *                  alloc_count_begin() and alloc_count_end(), and strace the calls between
 *                  the markers.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <valgrind/callgrind.h>

typedef void *fmi2Component;
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

static void logger(void *env, fmi2String name, fmi2Status status, fmi2String category, fmi2String message, ...) {
    (void)env; (void)name; (void)category;
    if (status >= 2) {
        va_list args;
        va_start(args, message);
        fprintf(stderr, "FMU: ");
        vfprintf(stderr, message, args);
        fprintf(stderr, "\n");
        va_end(args);
    }
}

typedef fmi2Component (*Instantiate)(fmi2String, int, fmi2String, fmi2String, const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
typedef fmi2Status (*Setup)(fmi2Component, fmi2Boolean, double, double, fmi2Boolean, double);
typedef fmi2Status (*Simple)(fmi2Component);
typedef fmi2Status (*SetReal)(fmi2Component, const fmi2ValueReference *, size_t, const double *);
typedef fmi2Status (*GetReal)(fmi2Component, const fmi2ValueReference *, size_t, double *);
typedef fmi2Status (*SetInteger)(fmi2Component, const fmi2ValueReference *, size_t, const int *);
typedef fmi2Status (*GetInteger)(fmi2Component, const fmi2ValueReference *, size_t, int *);
typedef fmi2Status (*DoStep)(fmi2Component, double, double, fmi2Boolean);
typedef void (*Free)(fmi2Component);

static void *symbol(void *lib, const char *name) {
    void *f = dlsym(lib, name);
    if (!f) {
        fprintf(stderr, "missing %s\n", name);
        exit(2);
    }
    return f;
}

static double *read_drive(const char *path, size_t *steps) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "cannot open %s\n", path);
        exit(2);
    }
    fseek(f, 0, SEEK_END);
    long bytes = ftell(f);
    fseek(f, 0, SEEK_SET);
    double *d = malloc(bytes);
    if (fread(d, 1, bytes, f) != (size_t)bytes) exit(2);
    fclose(f);
    *steps = bytes / (6 * sizeof(double));
    return d;
}

static double now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e9 + t.tv_nsec;
}

/* The value references of StewartCueing (modelDescription/StewartCueing.xml). */
static const fmi2ValueReference INPUTS[6] = {1, 2, 3, 4, 5, 6};
static const fmi2ValueReference METHOD = 47, ITERATIONS = 172;
static fmi2ValueReference POSE[18];

int main(int argc, char **argv) {
    if (argc < 7) {
        fprintf(stderr, "usage: cueing_host SO GUID RESOURCES METHOD MODE DRIVE...\n");
        return 2;
    }
    for (int i = 0; i < 18; i++) POSE[i] = 110 + i;
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 2;
    }
    Instantiate instantiate = (Instantiate)symbol(lib, "fmi2Instantiate");
    Setup setup = (Setup)symbol(lib, "fmi2SetupExperiment");
    Simple enter = (Simple)symbol(lib, "fmi2EnterInitializationMode");
    Simple exit_init = (Simple)symbol(lib, "fmi2ExitInitializationMode");
    SetReal set_real = (SetReal)symbol(lib, "fmi2SetReal");
    GetReal get_real = (GetReal)symbol(lib, "fmi2GetReal");
    SetInteger set_integer = (SetInteger)symbol(lib, "fmi2SetInteger");
    GetInteger get_integer = (GetInteger)symbol(lib, "fmi2GetInteger");
    DoStep do_step = (DoStep)symbol(lib, "fmi2DoStep");
    Simple terminate = (Simple)symbol(lib, "fmi2Terminate");
    Free free_instance = (Free)symbol(lib, "fmi2FreeInstance");
    const int method = atoi(argv[4]);
    const char *mode = argv[5];
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const double h = 1e-3;
    void (*count_begin)(void) = (void (*)(void))dlsym(RTLD_DEFAULT, "alloc_count_begin");
    void (*count_end)(void) = (void (*)(void))dlsym(RTLD_DEFAULT, "alloc_count_end");
    for (int d = 6; d < argc; d++) {
        size_t steps;
        double *drive = read_drive(argv[d], &steps);
        fmi2Component c = instantiate("cueing", 1, argv[2], argv[3], &callbacks, 0, 0);
        if (!c) return 3;
        setup(c, 0, 0.0, 0.0, 0, 0.0);
        set_integer(c, &METHOD, 1, &method);
        enter(c);
        if (exit_init(c) > 1) return 3;
        double pose[18];
        double sum = 0, largest = 0, largest_solve = 0, largest_plain = 0;
        int best_steps[3] = {-1, -1, -1}, best_iterations[3] = {-1, -1, -1};
        size_t warm = 0, quiet_steps = 0;
        const int quiet = strncmp(mode, "quiet:", 6) == 0;
        if (quiet) sscanf(mode + 6, "%zu:%zu", &warm, &quiet_steps);
        for (size_t i = 0; i + 1 < steps; i++) {
            int counted = 0;
            if (strncmp(mode, "count:", 6) == 0) {
                /* "count:D:S,D:S": this drive's listed steps. */
                const char *p = mode + 6;
                while (*p) {
                    int dd = atoi(p);
                    const char *colon = strchr(p, ':');
                    if (!colon) break;
                    if (dd == d - 6 && (size_t)atoi(colon + 1) == i) counted = 1;
                    const char *comma = strchr(colon, ',');
                    if (!comma) break;
                    p = comma + 1;
                }
            }
            if (quiet && d == 6 && i == warm) {
                if (count_begin) count_begin();
                getppid();
            }
            if (quiet && d == 6 && i == warm + quiet_steps) {
                getppid();
                if (count_end) count_end();
            }
            if (counted || strcmp(mode, "all") == 0) CALLGRIND_TOGGLE_COLLECT;
            double start = now_ns();
            set_real(c, INPUTS, 6, drive + 6 * i);
            fmi2Status s = do_step(c, i * h, h, 1);
            get_real(c, POSE, 18, pose);
            double spent = now_ns() - start;
            if (counted || strcmp(mode, "all") == 0) CALLGRIND_TOGGLE_COLLECT;
            if (counted) {
                char name[64];
                snprintf(name, sizeof name, "drive %d step %zu", d - 6, i);
                CALLGRIND_DUMP_STATS_AT(name);
            }
            if (s > 1) {
                fprintf(stderr, "doStep failed at step %zu of drive %d (status %d)\n", i, d - 6, s);
                return 4;
            }
            if (strcmp(mode, "time") == 0) {
                int iterations = 0;
                get_integer(c, &ITERATIONS, 1, &iterations);
                sum += spent;
                if (spent > largest) largest = spent;
                /* Steps at a solve: the period's multiples (10 ms at 1 ms steps by default). */
                if (i % 10 == 0) {
                    if (spent > largest_solve) largest_solve = spent;
                } else if (spent > largest_plain) {
                    largest_plain = spent;
                }
                if (i % 10 == 0) {
                    for (int k = 0; k < 3; k++) {
                        if (iterations > best_iterations[k]) {
                            for (int m = 2; m > k; m--) {
                                best_iterations[m] = best_iterations[m - 1];
                                best_steps[m] = best_steps[m - 1];
                            }
                            best_iterations[k] = iterations;
                            best_steps[k] = (int)i;
                            break;
                        }
                    }
                }
            }
        }
        if (strcmp(mode, "time") == 0) {
            printf("drive %d steps %zu mean_ns %.0f max_ns %.0f max_solve_ns %.0f max_plain_ns %.0f most_iterations",
                   d - 6, steps - 1, sum / (steps - 1), largest, largest_solve, largest_plain);
            for (int k = 0; k < 3; k++) printf(" %d:%d", best_steps[k], best_iterations[k]);
            printf("\n");
        }
        terminate(c);
        free_instance(c);
        free(drive);
    }
    return 0;
}
