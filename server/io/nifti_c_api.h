// nifti_clib's C API (nifti2_io.h), which has no extern "C" guard of its own.
// The C library headers it includes are pulled in first as C++ headers, so
// that the extern "C" block below does not wrap libstdc++'s templates.
#pragma once

#include <ctype.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>
#include <cctype>
#include <cinttypes>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

extern "C" {
#include <nifti2_io.h>
}
