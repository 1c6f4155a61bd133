#define SAPMVS_FUZZ_EXT ".txt"
#include "colmap_model_fuzz.inc"
