/* Glue of the Press FMU: the generic FMI wrapper's component functions (tc_fmu.h) on the native press model. */
#include "tc_press.h"

#define TC_GLUE tc_press
#define TC_GLUE_WHAT "the press"
#define TC_GLUE_STEP(model, dt, inputs, msg) ((void)(inputs), tc_press_step((model), (dt), (msg))) /* no inputs */
#include "tc_linear_glue.h"
