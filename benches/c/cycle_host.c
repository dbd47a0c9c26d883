/* The whole co-simulation cycle from a plain C host, as a simulator drives the platform FMU:
 * set the six leg forces, step 1 ms, read the twelve leg lengths and rates, with a leg-length
 * feedback around the neutral legs (so the platform stays near its pose for any run length).
 *
 *   cycle_host fmi2|fmi3 <binary.so> <GUID or token> rk4|dopri5 count   <cycles>
 *   cycle_host ...                                              loop <cycles> <runs>
 *   cycle_host ...                                              latency <cycles>
 *   cycle_host ...                                              threads <cycles> <threads>
 *   cycle_host ...                                              instantiate <count>
 *
 * count: no clock in the loop, for callgrind; set_forces, do_step and get_outputs are separate
 * non-inlined functions so that their inclusive instruction counts split the cycle.
 * loop: <runs> runs of <cycles> cycles each, the clock read only before and after each run (as
 * MuJoCo's own C loop is timed); prints microseconds per cycle of each run, their minimum and
 * their median. loop and latency first run cycles untimed for WARM_UP_SECONDS.
 * latency: clock_gettime around every cycle; prints percentiles in microseconds, and the cost of
 * one clock read (the median of empty intervals), which every sample includes once.
 * threads: that many threads, each with its own instance, warm up, then run the cycles at
 * once; prints steps per second.
 *
 * CYCLE_SCENARIO (environment) picks the motion: hover (default: the leg feedback above, no
 * stop touched), contact (power loss: zero forces; the platform falls onto its lower stops and
 * rests on them; count mode first runs 1500 uncounted cycles, so that every counted cycle is in
 * contact), nostops (hover with the end stops switched off: parameter stops = false),
 * nojoints (hover with the joint limits switched off: parameter joints = false), heavylegs
 * (hover with legs of 40 kg cylinders and 15 kg rods: leg.cylinderMass, leg.rodMass), drives
 * (hover with the default electric drives: drive = 1, I0 the holding current, the same feedback
 * through the drive's static model set as the voltages U),
 * hydraulics (hover with the default hydraulic servo legs: drive = 2, the holding pressures'
 * defaults, the valve commands of the controller's hydraulic mode from the same feedback: a
 * force loop on the measured pA, pB and the leg error through the flow; the host gets the 12
 * leg values and the 12 pressures),
 * powerunit (hydraulics with the power unit feeding the valves: hydraulic.supply = 1),
 * pumpfailure (hydraulic legs with every valve fully open and pS = 0 from the start: the stiff
 * regime of docs/model.md §10, where RK4 cuts each step into sub-steps within its stability
 * bound; the platform settles onto its lower stops within the first 1000 cycles),
 * logevents (FMI 2: hover with a logger that drops messages and logEvents on, so that the FMU
 * tracks passages through singular arrangements, which it skips when nobody can be told),
 * pose (hover; the host also gets the pose: r, R and angles, 15 values besides the 12 leg values).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef void *Instance;
typedef int (*Status1)(Instance);
static int fmi3;
static void *lib;
static const char *guid;
static int method;

/* FMI 2 */
typedef struct {
    void *logger, *allocate, *free, *step_finished, *environment;
} Callbacks2;
static Instance (*fmi2Instantiate)(const char *, int, const char *, const char *, const Callbacks2 *, int, int);
static int (*fmi2SetupExperiment)(Instance, int, double, double, int, double);
static int (*fmi2SetReal)(Instance, const unsigned *, size_t, const double *);
static int (*fmi2GetReal)(Instance, const unsigned *, size_t, double *);
static int (*fmi2SetInteger)(Instance, const unsigned *, size_t, const int *);
static int (*fmi2SetBoolean)(Instance, const unsigned *, size_t, const int *);
static int (*fmi2DoStep)(Instance, double, double, int);
static int (*fmi2SetDebugLogging)(Instance, int, size_t, const char *const *);
static void (*fmi2FreeInstance)(Instance);
static Status1 fmi2EnterInitializationMode, fmi2ExitInitializationMode;
/* FMI 3 */
static Instance (*fmi3InstantiateCoSimulation)(const char *, const char *, const char *, int, int, int, int,
                                               const unsigned *, size_t, void *, void *, void *);
static int (*fmi3EnterInitializationMode)(Instance, int, double, double, int, double);
static int (*fmi3SetFloat64)(Instance, const unsigned *, size_t, const double *, size_t);
static int (*fmi3GetFloat64)(Instance, const unsigned *, size_t, double *, size_t);
static int (*fmi3SetInt32)(Instance, const unsigned *, size_t, const int *, size_t);
static int (*fmi3SetBoolean)(Instance, const unsigned *, size_t, const _Bool *, size_t);
static int (*fmi3DoStep)(Instance, double, double, int, int *, int *, int *, double *);
static void (*fmi3FreeInstance)(Instance);
static Status1 fmi3ExitInitializationMode;

#define LOAD(f) do { *(void **)&f = dlsym(lib, #f); if (!f) { fprintf(stderr, "missing %s\n", #f); exit(2); } } while (0)

static const double H = 1e-3, L0 = 1.7550860729486566;
static double U0 = 5900.715, G = 2e5, D = 2e4;
static int stops_on = 1, joints_on = 1, log_events = 0;
static double leg_masses[2] = {0.0, 0.0};
static const unsigned FORCES2[6] = {1, 2, 3, 4, 5, 6};
static const unsigned LEGS2[12] = {121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132};
static const unsigned FORCES3[1] = {1};
static const unsigned LEGS3[2] = {121, 127};
static const unsigned METHOD_VR = 80, STOPS_VR = 170, JOINTS_VR = 310;
static const unsigned LEG_MASS_VRS[2] = {300, 301};
/* Electric drives: drive, I0, U; the default drive's holding current and volts per newton
 * R / (N k_t) = 0.4 / (2 pi / 0.02). */
static int drives_on = 0;
static const unsigned DRIVE_VR = 400, I0_VRS[6] = {410, 411, 412, 413, 414, 415};
/* hydraulic.supply: 1 feeds the hydraulic legs from the power unit (powerunit scenario). */
static const unsigned SUPPLY_MODE_VR = 570;
static int power_unit_on = 0;
static const unsigned VOLTAGES2[6] = {420, 421, 422, 423, 424, 425};
static const unsigned VOLTAGES3[1] = {420};
static const double HOLDING_CURRENT = 18.782559200529864, VOLTS_PER_NEWTON = 1.2732395447351628e-3;
static const unsigned *inputs2 = FORCES2, *inputs3 = FORCES3;
/* Hydraulic servo legs: valve, and pA, pB read with the legs; the controller's default force
 * loop gain (1/N), its leg-error gain through the flow (1/s) and the flow per unit opening at
 * pS / 2: A_A / (K sqrt(8 MPa)). */
static int hydraulic_on = 0, pump_failure_on = 0;
static const unsigned SUPPLY_PRESSURE_VR = 466;
static const unsigned VALVES2[6] = {460, 461, 462, 463, 464, 465};
static const unsigned VALVES3[1] = {460};
static const unsigned LEGS_PRESSURES2[24] = {121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132,
                                             510, 511, 512, 513, 514, 515, 516, 517, 518, 519, 520, 521};
static const unsigned LEGS_PRESSURES3[4] = {121, 127, 510, 516};
/* The pose read with the legs: r, R, angles (27 values in all). */
static int pose_on = 0;
static const unsigned LEGS_POSE2[27] = {121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132, 100, 101,
                                        102, 106, 107, 108, 109, 110, 111, 112, 113, 114, 115, 116, 117};
static const unsigned LEGS_POSE3[5] = {121, 127, 100, 106, 115};
static const double FORCE_GAIN = 1.5e-5, LENGTH_GAIN = 50.0, AREA_A = 3.1172453105244723e-3,
                    AREA_B = 2.0993692907613796e-3, OPENING_PER_RATE = 1.2371183800845102;

/* A logger that drops every message: the FMU can deliver logEvents, nothing is printed. */
static void ignore_message(void *env, const char *name, int status, const char *category, const char *message, ...) {
    (void)env; (void)name; (void)status; (void)category; (void)message;
}

static Instance make(void) {
    Instance c;
    if (fmi3) {
        c = fmi3InstantiateCoSimulation("cycle", guid, NULL, 0, 0, 0, 0, NULL, 0, NULL, NULL, NULL);
        if (!c || fmi3EnterInitializationMode(c, 0, 0.0, 0.0, 0, 0.0)) exit(3);
        fmi3SetInt32(c, &METHOD_VR, 1, &method, 1);
        _Bool on = stops_on, joints = joints_on;
        fmi3SetBoolean(c, &STOPS_VR, 1, &on, 1);
        fmi3SetBoolean(c, &JOINTS_VR, 1, &joints, 1);
        fmi3SetFloat64(c, &LEG_MASS_VRS[0], 1, &leg_masses[0], 1);
        fmi3SetFloat64(c, &LEG_MASS_VRS[1], 1, &leg_masses[1], 1);
        if (drives_on) {
            double i0[6] = {HOLDING_CURRENT, HOLDING_CURRENT, HOLDING_CURRENT, HOLDING_CURRENT, HOLDING_CURRENT,
                            HOLDING_CURRENT};
            fmi3SetInt32(c, &DRIVE_VR, 1, &drives_on, 1);
            if (drives_on == 1) fmi3SetFloat64(c, I0_VRS, 1, i0, 6);
            if (power_unit_on) fmi3SetInt32(c, &SUPPLY_MODE_VR, 1, &power_unit_on, 1);
        }
        const double no_supply = 0.0;
        if (pump_failure_on && fmi3SetFloat64(c, &SUPPLY_PRESSURE_VR, 1, &no_supply, 1)) exit(3);
        if (fmi3ExitInitializationMode(c)) exit(3);
    } else {
        static const Callbacks2 quiet = {0};
        static const Callbacks2 logging = {.logger = (void *)ignore_message};
        c = fmi2Instantiate("cycle", 1, guid, NULL, log_events ? &logging : &quiet, 0, 0);
        if (c && log_events) {
            const char *category = "logEvents";
            if (fmi2SetDebugLogging(c, 1, 1, &category)) exit(3);
        }
        if (!c || fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) || fmi2EnterInitializationMode(c)) exit(3);
        fmi2SetInteger(c, &METHOD_VR, 1, &method);
        fmi2SetBoolean(c, &STOPS_VR, 1, &stops_on);
        fmi2SetBoolean(c, &JOINTS_VR, 1, &joints_on);
        fmi2SetReal(c, LEG_MASS_VRS, 2, leg_masses);
        if (drives_on) {
            double i0[6] = {HOLDING_CURRENT, HOLDING_CURRENT, HOLDING_CURRENT, HOLDING_CURRENT, HOLDING_CURRENT,
                            HOLDING_CURRENT};
            fmi2SetInteger(c, &DRIVE_VR, 1, &drives_on);
            if (drives_on == 1) fmi2SetReal(c, I0_VRS, 6, i0);
            if (power_unit_on) fmi2SetInteger(c, &SUPPLY_MODE_VR, 1, &power_unit_on);
        }
        const double no_supply = 0.0;
        if (pump_failure_on && fmi2SetReal(c, &SUPPLY_PRESSURE_VR, 1, &no_supply)) exit(3);
        if (fmi2ExitInitializationMode(c)) exit(3);
    }
    return c;
}

static void release(Instance c) {
    if (fmi3) fmi3FreeInstance(c); else fmi2FreeInstance(c);
}

__attribute__((noinline)) static void set_forces(Instance c, const double *legs) {
    double f[6];
    if (pump_failure_on)
        for (int k = 0; k < 6; k++) f[k] = 1.0;
    else
        for (int k = 0; k < 6; k++) f[k] = U0 + G * (L0 - legs[k]) - D * legs[6 + k];
    if (hydraulic_on && !pump_failure_on)
        for (int k = 0; k < 6; k++)
            f[k] = FORCE_GAIN * (f[k] - (legs[12 + k] * AREA_A - legs[18 + k] * AREA_B))
                   + OPENING_PER_RATE * LENGTH_GAIN * (L0 - legs[k]);
    int s = fmi3 ? fmi3SetFloat64(c, inputs3, 1, f, 6) : fmi2SetReal(c, inputs2, 6, f);
    if (s) exit(4);
}

__attribute__((noinline)) static void do_step(Instance c, double t) {
    int event, terminate, early;
    double last;
    int s = fmi3 ? fmi3DoStep(c, t, H, 1, &event, &terminate, &early, &last) : fmi2DoStep(c, t, H, 1);
    if (s) exit(5);
}

__attribute__((noinline)) static void get_outputs(Instance c, double *legs) {
    int s = hydraulic_on ? (fmi3 ? fmi3GetFloat64(c, LEGS_PRESSURES3, 4, legs, 24)
                                 : fmi2GetReal(c, LEGS_PRESSURES2, 24, legs))
            : pose_on    ? (fmi3 ? fmi3GetFloat64(c, LEGS_POSE3, 5, legs, 27) : fmi2GetReal(c, LEGS_POSE2, 27, legs))
                         : (fmi3 ? fmi3GetFloat64(c, LEGS3, 2, legs, 12) : fmi2GetReal(c, LEGS2, 12, legs));
    if (s) exit(6);
}

__attribute__((noinline)) static void run_cycles(Instance c, long n, double *legs, long first) {
    for (long i = first; i < first + n; i++) {
        set_forces(c, legs);
        do_step(c, i * H);
        get_outputs(c, legs);
    }
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* Cycles for WARM_UP_SECONDS before anything is timed, so that cold caches and branch
 * predictors are not; returns how many, so that the timed cycles go on from there. */
static const double WARM_UP_SECONDS = 0.3;
static long warm_up_cycles(Instance c, double *legs) {
    long done = 0;
    double t0 = now();
    while (now() - t0 < WARM_UP_SECONDS) {
        run_cycles(c, 1000, legs, done);
        done += 1000;
    }
    return done;
}

static int compare(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *x, long n) {
    qsort(x, n, sizeof *x, compare);
    return n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
}

/* What one sample of the latency loop measures when the cycle takes no time: the median of
 * 10^5 empty intervals between two clock reads. */
static double clock_read_seconds(void) {
    enum { N = 100000 };
    static double empty[N];
    for (long i = 0; i < N; i++) {
        double t0 = now();
        empty[i] = now() - t0;
    }
    return median(empty, N);
}

typedef struct { long n; double seconds; pthread_barrier_t *warm; } Job;

static void *thread_job(void *arg) {
    Job *job = arg;
    Instance c = make();
    double legs[27];
    get_outputs(c, legs);
    long first = warm_up_cycles(c, legs);
    pthread_barrier_wait(job->warm); /* every thread starts its timed cycles together */
    double t0 = now();
    run_cycles(c, job->n, legs, first);
    job->seconds = now() - t0;
    release(c);
    return NULL;
}

int main(int argc, char **argv) {
    if (argc < 7) {
        fprintf(stderr, "usage: %s fmi2|fmi3 binary guid rk4|dopri5 count|latency|threads|instantiate n [threads]\n", argv[0]);
        return 2;
    }
    fmi3 = strcmp(argv[1], "fmi3") == 0;
    lib = dlopen(argv[2], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "dlopen: %s\n", dlerror()); return 2; }
    guid = argv[3];
    method = strcmp(argv[4], "rk4") == 0 ? 2 : 1;
    const char *mode = argv[5];
    long n = atol(argv[6]);
    const char *scenario = getenv("CYCLE_SCENARIO");
    long warm_up = 0;
    if (scenario && strcmp(scenario, "contact") == 0) {
        U0 = G = D = 0.0;
        warm_up = 1500;
    } else if (scenario && strcmp(scenario, "nostops") == 0) {
        stops_on = 0;
    } else if (scenario && strcmp(scenario, "nojoints") == 0) {
        joints_on = 0;
    } else if (scenario && strcmp(scenario, "heavylegs") == 0) {
        leg_masses[0] = 40.0;
        leg_masses[1] = 15.0;
    } else if (scenario && strcmp(scenario, "drives") == 0) {
        drives_on = 1;
        inputs2 = VOLTAGES2;
        inputs3 = VOLTAGES3;
        U0 = HOLDING_CURRENT * 0.4;
        G *= VOLTS_PER_NEWTON;
        D *= VOLTS_PER_NEWTON;
    } else if (scenario && (strcmp(scenario, "hydraulics") == 0 || strcmp(scenario, "powerunit") == 0 ||
                            strcmp(scenario, "pumpfailure") == 0)) {
        drives_on = 2;
        hydraulic_on = 1;
        power_unit_on = strcmp(scenario, "powerunit") == 0;
        pump_failure_on = strcmp(scenario, "pumpfailure") == 0;
        inputs2 = VALVES2;
        inputs3 = VALVES3;
    } else if (scenario && strcmp(scenario, "pose") == 0) {
        pose_on = 1;
    } else if (scenario && strcmp(scenario, "logevents") == 0) {
        if (fmi3) { fprintf(stderr, "CYCLE_SCENARIO=logevents is for FMI 2\n"); return 2; }
        log_events = 1;
    } else if (scenario && strcmp(scenario, "hover") != 0) {
        fprintf(stderr, "CYCLE_SCENARIO must be hover, contact, nostops, nojoints, heavylegs, drives, hydraulics, "
                        "powerunit, pumpfailure, pose or logevents\n");
        return 2;
    }
    if (fmi3) {
        LOAD(fmi3InstantiateCoSimulation); LOAD(fmi3EnterInitializationMode); LOAD(fmi3ExitInitializationMode);
        LOAD(fmi3SetFloat64); LOAD(fmi3GetFloat64); LOAD(fmi3SetInt32); LOAD(fmi3SetBoolean); LOAD(fmi3DoStep);
        LOAD(fmi3FreeInstance);
    } else {
        LOAD(fmi2Instantiate); LOAD(fmi2SetupExperiment); LOAD(fmi2EnterInitializationMode);
        LOAD(fmi2ExitInitializationMode); LOAD(fmi2SetReal); LOAD(fmi2GetReal); LOAD(fmi2SetInteger);
        LOAD(fmi2SetBoolean); LOAD(fmi2SetDebugLogging);
        LOAD(fmi2DoStep); LOAD(fmi2FreeInstance);
    }
    if (strcmp(mode, "instantiate") == 0) {
        double t0 = now();
        for (long i = 0; i < n; i++) release(make());
        printf("instantiate+initialise+free: %.2f us each (%ld)\n", 1e6 * (now() - t0) / n, n);
        return 0;
    }
    if (strcmp(mode, "threads") == 0) {
        int threads = argc > 7 ? atoi(argv[7]) : 1;
        if (threads < 1 || threads > 64) { fprintf(stderr, "threads must be 1 to 64\n"); return 2; }
        pthread_t ids[64];
        Job jobs[64];
        pthread_barrier_t warm;
        pthread_barrier_init(&warm, NULL, threads + 1);
        for (int i = 0; i < threads; i++) {
            jobs[i].n = n;
            jobs[i].warm = &warm;
            pthread_create(&ids[i], NULL, thread_job, &jobs[i]);
        }
        pthread_barrier_wait(&warm);
        double t0 = now();
        for (int i = 0; i < threads; i++) pthread_join(ids[i], NULL);
        double wall = now() - t0;
        printf("threads %d: %ld cycles each, %.0f cycles/s in total, %.3f us per cycle per thread\n", threads, n,
               threads * n / wall, 1e6 * jobs[0].seconds / n);
        return 0;
    }
    Instance c = make();
    double legs[27];
    get_outputs(c, legs);
    if (strcmp(mode, "count") == 0) {
        /* Uncounted: the same calls, outside the counted functions. */
        for (long i = 0; i < warm_up; i++) {
            double f[6] = {0, 0, 0, 0, 0, 0};
            int s = fmi3 ? fmi3SetFloat64(c, FORCES3, 1, f, 6) : fmi2SetReal(c, FORCES2, 6, f);
            int event, terminate, early;
            double last;
            s |= fmi3 ? fmi3DoStep(c, i * H, H, 1, &event, &terminate, &early, &last) : fmi2DoStep(c, i * H, H, 1);
            s |= fmi3 ? fmi3GetFloat64(c, LEGS3, 2, legs, 12) : fmi2GetReal(c, LEGS2, 12, legs);
            if (s) exit(7);
        }
        run_cycles(c, n, legs, warm_up);
    } else if (strcmp(mode, "loop") == 0) {
        int runs = argc > 7 ? atoi(argv[7]) : 5;
        if (runs < 1 || runs > 1000) { fprintf(stderr, "runs must be 1 to 1000\n"); return 2; }
        long first = warm_up_cycles(c, legs);
        double per_cycle[1000];
        printf("loop of %ld cycles, %d runs, clock outside the loop (us per cycle):", n, runs);
        for (int r = 0; r < runs; r++) {
            double t0 = now();
            run_cycles(c, n, legs, first + (long)r * n);
            per_cycle[r] = 1e6 * (now() - t0) / n;
            printf(" %.3f", per_cycle[r]);
        }
        double middle = median(per_cycle, runs); /* sorts them */
        printf("; min %.3f median %.3f\n", per_cycle[0], middle);
    } else {
        double *dt = malloc(n * sizeof *dt);
        if (!dt) return 2;
        memset(dt, 0, n * sizeof *dt); /* touch every page before the clock runs */
        double clock_read = clock_read_seconds();
        long first = warm_up_cycles(c, legs);
        double clock0 = now(), clock1 = now();
        for (long i = 0; i < n; i++) {
            double t0 = now();
            set_forces(c, legs);
            do_step(c, (first + i) * H);
            get_outputs(c, legs);
            dt[i] = now() - t0;
        }
        (void)clock0;
        double overhead = now() - clock1;
        double sum = 0;
        for (long i = 0; i < n; i++) sum += dt[i];
        qsort(dt, n, sizeof *dt, compare);
        printf("latency over %ld cycles (us): mean %.3f p50 %.3f p99 %.3f p99.9 %.3f max %.1f; loop %.2f s; "
               "each sample includes one clock read, %.3f us\n", n,
               1e6 * sum / n, 1e6 * dt[n / 2], 1e6 * dt[(long)(n * 0.99)], 1e6 * dt[(long)(n * 0.999)],
               1e6 * dt[n - 1], overhead, 1e6 * clock_read);
        free(dt);
    }
    printf("final leg 1: %.12f m\n", legs[0]);
    release(c);
    return 0;
}
