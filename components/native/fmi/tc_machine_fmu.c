/* Glue of the DrawingMachine FMU: the generic FMI wrapper's component functions (tc_fmu.h) on the native
 * drawing-machine model. */
#include "tc_machine.h"

#define TC_GLUE tc_machine
#define TC_GLUE_WHAT "the drawing machine"
#define TC_GLUE_STEP(model, dt, inputs, msg) tc_machine_step((model), (dt), (inputs)[0], (msg)) /* pull_force */
#include "tc_linear_glue.h"
