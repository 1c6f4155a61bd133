#define SAPMVS_FUZZ_EXT ".bin"
#include "colmap_model_fuzz.inc"
