/* The fixed-step loop of the co-simulation master in C (C11, standard library only): the data the Python master
 * hands over and the one function that runs it. tribocosim.cosim.engine.native_loop fills these structs.
 *
 * The loop takes macro steps of Jacobi or Gauss-Seidel with the coupling values held over the step (extrapolation
 * order 0) on FMI 2.0 co-simulation slaves that the Python master has loaded, instantiated, parameterized and
 * initialized; it calls each slave's FMI functions through the pointers of its loaded library, in the order and
 * with the batches of tribocosim.cosim.engine.algorithms and .system, so that it computes what the Python loop
 * computes, bit for bit. It records the scene's output variables at every communication point into memory.
 *
 * It never saves an FMU state: a step that an FMU discards, or that gives a non-finite linked or recorded value,
 * stops the loop (TCM_STOPPED) with the FMUs past the step; the Python master then repeats the run with its own
 * loop, which can roll back and halve the step. Errors of FMI calls stop it too (TCM_FMI_ERROR), naming the slave
 * and the function. No global mutable state: everything lives in the caller's structs.
 */
#ifndef TC_MASTER_H
#define TC_MASTER_H

#include <stddef.h>
#include <stdint.h>

#include "fmi2FunctionTypes.h"

#if defined(_WIN32)
#  define TCM_API __declspec(dllexport)
#else
#  define TCM_API __attribute__((visibility("default")))
#endif

/* the outcome of tcm_run */
enum tcm_status {
    TCM_DONE = 0,      /* the steps asked for are taken (or the end of the grid is reached) */
    TCM_STOPPED = 1,   /* a step was discarded or gave a non-finite value: the Python loop takes over */
    TCM_FMI_ERROR = 2  /* an FMI function returned an error status: see tcm_state.failed_* */
};

/* the type of a recorded variable */
enum tcm_kind { TCM_REAL = 0, TCM_INTEGER = 1, TCM_BOOLEAN = 2 };

/* One slave: its instance and the FMI functions of its loaded library that the loop calls. */
typedef struct tcm_slave {
    fmi2Component component;
    fmi2SetRealTYPE *set_real;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2GetBooleanTYPE *get_boolean;
    fmi2DoStepTYPE *do_step;
    double wall_time;     /* s spent inside this slave's FMI calls (added to) */
    int64_t do_steps;     /* fmi2DoStep calls (added to) */
    double current_time;  /* the start of its last fmi2DoStep (updated; for messages) */
} tcm_slave;

/* One batched fmi2Get call: `n_vrs` value references of one kind of one slave, and where each value goes:
 * value vrs[pos[j]] to destination dst[j], j < n_dst (a link's coupling value, or a recorded column). */
typedef struct tcm_get {
    int slave;
    int kind;
    size_t n_vrs;
    const fmi2ValueReference *vrs;
    size_t n_dst;
    const int *pos;
    const int *dst;
} tcm_get;

/* One batched fmi2SetReal call: the inputs vrs[j] of one slave take the coupling values of links link[j]. */
typedef struct tcm_set {
    int slave;
    size_t n;
    const fmi2ValueReference *vrs;
    const int *link;
} tcm_set;

/* The rig: slaves, links as batched calls, the scheme, the recorded variables and the time grid. Per slave i its
 * set calls are sets[set_first[i]] .. sets[set_first[i + 1] - 1], its output reads gets[get_first[i]] ..
 * gets[get_first[i + 1] - 1] (in the order the Python system makes them). */
typedef struct tcm_rig {
    size_t n_slaves;
    tcm_slave *slaves;
    size_t n_links;
    const int *link_source;      /* the slave whose output each link reads */
    const size_t *set_first;     /* n_slaves + 1 */
    const tcm_set *sets;
    const size_t *get_first;     /* n_slaves + 1 */
    const tcm_get *gets;
    const int *feeds;            /* per slave: an output refresh sets its inputs first (propagate, has inputs, may
                                  * feed through) */
    const int *eval_order;       /* the order of the output refresh */
    const int *sequence;         /* the Gauss-Seidel order */
    int gauss_seidel;            /* 0: Jacobi, 1: Gauss-Seidel */
    int propagate;               /* output_update = "propagate" */
    size_t n_columns;            /* recorded variables */
    size_t n_record_gets;
    const tcm_get *record_gets;  /* columns read from the slaves (dst: the column) */
    size_t n_from_links;
    const int *from_link_column; /* columns that are a link's coupling value */
    const int *from_link;
    double start;                /* the time grid: t = start + n tick */
    double tick;
    int64_t macro_ticks;
    int64_t end_ticks;
} tcm_rig;

/* What the loop changes: the tick, the coupling values, the inputs last set, the recorded rows, and on a stop or an
 * error what failed. */
typedef struct tcm_state {
    int64_t n;                   /* the tick of the last accepted communication point */
    double *y;                   /* n_links: each link's coupling value */
    double *written;             /* n_links: the value each link's input was last set to */
    unsigned char *written_ok;   /* n_slaves: written[] holds slave i's inputs */
    unsigned char *stepped;      /* n_slaves: scratch */
    double *values;              /* scratch: at least n_links and the largest n_vrs of a get */
    double *held;                /* scratch, n_links: Gauss-Seidel's propagated inputs */
    fmi2Integer *ints;           /* scratch: at least the largest n_vrs of a get */
    double *row;                 /* scratch, n_columns */
    double *times;               /* capacity: the time of each recorded row */
    double *rows;                /* capacity x n_columns: the recorded rows */
    size_t capacity;
    size_t n_rows;               /* rows written (added to) */
    int64_t steps;               /* accepted steps (added to) */
    double min_step;             /* the shortest accepted step (updated) */
    double max_step;             /* the longest accepted step (updated) */
    int failed_slave;            /* TCM_STOPPED or TCM_FMI_ERROR: the slave, -1 for a recorded value */
    int failed_status;           /* its FMI status */
    const char *failed_function; /* the FMI function, or "non-finite output" */
    double failed_time;          /* the start of the step that failed */
} tcm_state;

/* Take up to max_steps accepted macro steps from state->n (fewer at the end of the grid or when state->capacity rows
 * are written); returns a tcm_status. */
TCM_API int tcm_run(const tcm_rig *rig, tcm_state *state, int64_t max_steps);

/* The output refresh at the current communication point (the slaves in rig->eval_order; one that may feed through
 * gets its inputs set to y first when rig->propagate), as tribocosim.cosim.engine.system.CoupledSystem.refresh. */
TCM_API int tcm_refresh(const tcm_rig *rig, tcm_state *state);

/* The loop Jacobian by probing, as CoupledSystem.probe_feedthrough: for each link j with probe[j], the input
 * target_vrs[j] of slave targets[j] is set to u + delta (u = y[j], delta = 1e-6 max(1, |u|)), the slave's linked
 * outputs read, the input set back to u and the outputs read again; jac[k m + j] = (y_k(u + delta) - y_k(u)) / delta
 * and dep[k m + j] = |jac| > 1e-8 max(1, |y_k|) / max(1, |u|) for the links k the slave's outputs feed (m links).
 * Afterwards y holds its values from before and no slave's inputs count as written. `scratch` holds 2 m doubles. */
TCM_API int tcm_probe(const tcm_rig *rig, tcm_state *state, const int *targets, const fmi2ValueReference *target_vrs,
                      const unsigned char *probe, double *jac, unsigned char *dep, double *scratch);

/* Read the recorded variables at the current communication point and append them as a row (the row of the start
 * point); a non-finite one stops (TCM_STOPPED). */
TCM_API int tcm_record_row(const tcm_rig *rig, tcm_state *state);

/* FMU log messages: the FMI 2.0 logger (variadic) formats a message and hands it to env->sink with env->key. */
typedef void tcm_sink(void *key, int status, const char *message);
typedef struct tcm_log_env {
    tcm_sink *sink;
    void *key;
} tcm_log_env;

TCM_API void tcm_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                        fmi2String message, ...);
/* The memory callbacks of FMI 2.0 (calloc and free). */
TCM_API void *tcm_allocate_memory(size_t n, size_t size);
TCM_API void tcm_free_memory(void *block);

#endif
