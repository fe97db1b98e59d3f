/* stair: an FMI 3.0 co-simulation FMU with the interface and behaviour of the Modelica Association's Reference FMU
 * `Stair` (written here from its description, not copied: no registry package ships the Reference FMUs): one Int32
 * output `counter`, 1 at the start, going up by 1 at each whole second. */
#include <math.h>
#include <stddef.h>

#define TOKEN "{silrig-stair-0001}"

typedef struct {
    int counter;
    char error[200];
} Model;

static int model_start(Model *m, const char *resources) {
    (void)resources;
    m->counter = 1;
    return 1;
}

/* A small margin: the rig's step ends at tick x dt, which lands a hair below a whole second for some dt. */
static void model_step(Model *m, double time_s) { m->counter = 1 + (int)floor(time_s + 1e-9); }

static int *model_int32(Model *m, unsigned int vr) { return vr == 1 ? &m->counter : NULL; }

#include "../int32_outputs.c"
