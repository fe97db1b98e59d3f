/* The FMI 3.0 functions this FMU does not offer: lag3's list, less fmi3GetInt32 (its outputs are Int32) and with the
 * state functions (it keeps none an importer can save). */
#define SILRIG_OWN_GET_INT32
#define SILRIG_NO_STATE
#include "../lag3/unsupported.c"
