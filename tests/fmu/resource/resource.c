/* resource: an FMI 3.0 co-simulation FMU with the interface and behaviour of the Modelica Association's Reference
 * FMU `Resource` (written here from its description, not copied: no registry package ships the Reference FMUs): at
 * instantiation it reads the file y.txt from its resources/ folder, and its one Int32 output `y` is the code of that
 * file's first character (97 for the "a" it ships). An FMU whose resources the importer did not unpack, or put
 * elsewhere than it said, cannot start: it logs the path it tried. */
#include <stddef.h>
#include <stdio.h>

#define TOKEN "{silrig-resource-0001}"

typedef struct {
    int y;
    char error[200];
} Model;

static int model_start(Model *m, const char *resources) {
    char path[4096];
    snprintf(path, sizeof path, "%sy.txt", resources);
    FILE *f = fopen(path, "rb");
    int c = f ? fgetc(f) : EOF;
    if (f) {
        fclose(f);
    }
    if (c == EOF) {
        snprintf(m->error, sizeof m->error, "cannot read a character from %.150s", path);
        return 0;
    }
    m->y = c;
    return 1;
}

static void model_step(Model *m, double time_s) { (void)m; (void)time_s; }

static int *model_int32(Model *m, unsigned int vr) { return vr == 1 ? &m->y : NULL; }

#include "../int32_outputs.c"
