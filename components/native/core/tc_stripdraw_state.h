/* The strip-draw model's state image and the backup of its state across a step (the format is in
 * tc_stripdraw_state.c). The model derives its contact weights and friction limits again after tc_sd_state_read and
 * tc_sd_restore. */
#ifndef TC_STRIPDRAW_STATE_H
#define TC_STRIPDRAW_STATE_H

#include <stddef.h>

#include "tc_common.h"

struct tc_stripdraw;

/* the bytes of the state image of a model of n nodes */
size_t tc_sd_state_size(size_t n);

/* the state image of m into buf (tc_sd_state_size bytes) */
void tc_sd_state_write(const struct tc_stripdraw *m, void *buf);

/* m's state from an image; TC_ERROR (m unchanged) when the image is not one of this model: size, magic, version,
 * node count, a contact flag that is not 0 or 1 */
int tc_sd_state_read(struct tc_stripdraw *m, const void *buf, size_t size, tc_msg msg);

/* exchange the bar's arrays U, V, A, fprev with the backup's (bar_in_backup flips) */
void tc_sd_swap_bar(struct tc_stripdraw *m);

/* the state before a step into the backup (the bar's arrays exchanged, the rest copied) */
void tc_sd_backup(struct tc_stripdraw *m);

/* back to the state of tc_sd_backup (time and n_steps change only with a step that is taken) */
void tc_sd_restore(struct tc_stripdraw *m);

#endif
