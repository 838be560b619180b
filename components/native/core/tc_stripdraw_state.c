/* The strip-draw model's state as a byte image, and its backup across a step (tc_stripdraw_state.h).
 *
 * The image (native byte order): a header (magic "TCSD", format version, node count), the arrays U, V, A, Up, beta,
 * slip_rate, fprev, the scalars time, reaction, normal_force, grip_velocity, beta_removed, beta_produced, beta_hi,
 * the counts n_steps, clamp_count (int64), then the contact flags (one byte each). Everything else is fixed by the
 * parameters or derived from the state (the contact weights from U, the friction limits from beta, the normal force
 * and the velocity), which the model derives again after reading an image or restoring a backup.
 *
 * The backup of a step keeps the bar's arrays U, V, A, fprev by exchanging them with the backup's (the step's first
 * interval reads them there and writes its own), and copies the rest: a refused step leaves the model as it was,
 * bit for bit.
 */
#include "tc_stripdraw_state.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "tc_stripdraw_model.h"

#define STATE_MAGIC 0x44534354u /* "TCSD" in little-endian bytes */
#define STATE_VERSION 2u
#define STATE_HEADER 16
#define N_STATE_ARRAYS 7
#define N_STATE_DOUBLES 7
#define N_STATE_INTS 2

size_t tc_sd_state_size(size_t n) {
    return STATE_HEADER + sizeof(double) * (N_STATE_ARRAYS * n + N_STATE_DOUBLES) + sizeof(int64_t) * N_STATE_INTS +
           n;
}

/* the state image; its slip rates from slip, as they stand (h = 0) or as |slip[i]| / h */
static void write_image(const struct tc_stripdraw *m, unsigned char *b, const double *slip, double h) {
    const size_t n = m->n, nb = n * sizeof(double);
    const uint32_t head[2] = {STATE_MAGIC, STATE_VERSION};
    const uint64_t nn = (uint64_t)n;
    memcpy(b, head, sizeof head);
    memcpy(b + 8, &nn, sizeof nn);
    b += STATE_HEADER;
    const double *arrays[N_STATE_ARRAYS] = {m->U, m->V, m->A, m->Up, m->beta, slip, m->fprev};
    for (int k = 0; k < N_STATE_ARRAYS; ++k, b += nb) {
        if (arrays[k] != slip || !(h > 0)) {
            memcpy(b, arrays[k], nb);
            continue;
        }
        for (size_t i = 0; i < n; ++i) {
            const double rate = fabs(slip[i]) / h;
            memcpy(b + i * sizeof rate, &rate, sizeof rate);
        }
    }
    const double scalars[N_STATE_DOUBLES] = {m->time, m->reaction, m->normal_force, m->grip_velocity,
                                             m->beta_removed, m->beta_produced, m->beta_hi};
    memcpy(b, scalars, sizeof scalars);
    b += sizeof scalars;
    const int64_t counts[N_STATE_INTS] = {(int64_t)m->n_steps, (int64_t)m->clamp_count};
    memcpy(b, counts, sizeof counts);
    b += sizeof counts;
    memcpy(b, m->contact, n);
}

static void read_image(struct tc_stripdraw *m, const unsigned char *b) {
    const size_t n = m->n, nb = n * sizeof(double);
    b += STATE_HEADER;
    double *arrays[N_STATE_ARRAYS] = {m->U, m->V, m->A, m->Up, m->beta, m->slip_rate, m->fprev};
    for (int k = 0; k < N_STATE_ARRAYS; ++k, b += nb) memcpy(arrays[k], b, nb);
    double scalars[N_STATE_DOUBLES];
    memcpy(scalars, b, sizeof scalars);
    b += sizeof scalars;
    m->time = scalars[0];
    m->reaction = scalars[1];
    m->normal_force = scalars[2];
    m->grip_velocity = scalars[3];
    m->beta_removed = scalars[4];
    m->beta_produced = scalars[5];
    m->beta_hi = scalars[6];
    int64_t counts[N_STATE_INTS];
    memcpy(counts, b, sizeof counts);
    b += sizeof counts;
    m->n_steps = (long long)counts[0];
    m->clamp_count = (long long)counts[1];
    memcpy(m->contact, b, n);
    m->slip_h = 0.0;
}

void tc_sd_swap_bar(struct tc_stripdraw *m) {
    double **cur[4] = {&m->U, &m->V, &m->A, &m->fprev}, **bak[4] = {&m->bU, &m->bV, &m->bA, &m->bfprev};
    for (int k = 0; k < 4; ++k) {
        double *t = *cur[k];
        *cur[k] = *bak[k];
        *bak[k] = t;
    }
    m->bar_in_backup = !m->bar_in_backup;
}

/* the doubles of the model a step changes besides its arrays (time changes only with a step that is taken) */
static void step_scalars(struct tc_stripdraw *m, double *s[TC_SD_STEP_SCALARS]) {
    double *all[TC_SD_STEP_SCALARS] = {&m->reaction,      &m->normal_force, &m->grip_velocity, &m->beta_removed,
                                   &m->beta_produced, &m->beta_hi,      &m->slip_h};
    memcpy(s, all, sizeof all);
}

void tc_sd_backup(struct tc_stripdraw *m) {
    const size_t nb = m->n * sizeof(double);
    tc_sd_swap_bar(m);
    memcpy(m->bUp, m->Up, nb);
    memcpy(m->bbeta, m->beta, nb);
    memcpy(m->bslip, m->slip_h > 0 ? m->dU : m->slip_rate, nb);
    memcpy(m->bcontact, m->contact, m->n);
    double *s[TC_SD_STEP_SCALARS];
    step_scalars(m, s);
    for (int k = 0; k < TC_SD_STEP_SCALARS; ++k) m->b_scalars[k] = *s[k];
    m->b_clamp_count = m->clamp_count;
}

void tc_sd_restore(struct tc_stripdraw *m) {
    const size_t nb = m->n * sizeof(double);
    tc_sd_swap_bar(m); /* the state of the step's start into U, V, A, fprev, whether an interval was taken or not */
    m->bar_in_backup = 0;
    memcpy(m->Up, m->bUp, nb);
    memcpy(m->beta, m->bbeta, nb);
    memcpy(m->contact, m->bcontact, m->n);
    double *s[TC_SD_STEP_SCALARS];
    step_scalars(m, s);
    for (int k = 0; k < TC_SD_STEP_SCALARS; ++k) *s[k] = m->b_scalars[k];
    m->clamp_count = m->b_clamp_count;
    memcpy(m->slip_h > 0 ? m->dU : m->slip_rate, m->bslip, nb); /* the slip rates as tc_sd_backup found them */
}


void tc_sd_state_write(const struct tc_stripdraw *m, void *buf) {
    write_image(m, buf, m->slip_h > 0 ? m->dU : m->slip_rate, m->slip_h);
}

int tc_sd_state_read(struct tc_stripdraw *m, const void *buf, size_t size, tc_msg msg) {
    const unsigned char *b = buf;
    if (b == NULL || size != m->state_size)
        return tc_fail(msg, TC_ERROR, "strip-draw state image has %zu bytes; this model's has %zu",
                       b == NULL ? (size_t)0 : size, m->state_size);
    uint32_t head[2];
    uint64_t nn;
    memcpy(head, b, sizeof head);
    memcpy(&nn, b + 8, sizeof nn);
    if (head[0] != STATE_MAGIC || head[1] != STATE_VERSION)
        return tc_fail(msg, TC_ERROR, "not a strip-draw state image (version %u of this format is read)",
                       (unsigned)STATE_VERSION);
    if (nn != (uint64_t)m->n)
        return tc_fail(msg, TC_ERROR, "strip-draw state image has %llu nodes; this model has %zu",
                       (unsigned long long)nn, m->n);
    const unsigned char *contact = b + size - m->n;
    for (size_t i = 0; i < m->n; ++i)
        if (contact[i] > 1) return tc_fail(msg, TC_ERROR, "strip-draw state image has a contact flag that is not 0/1");
    read_image(m, b);
    return TC_OK;
}
