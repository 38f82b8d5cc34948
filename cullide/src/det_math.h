// det_math.h: the former name of scene_math.h (platform-independent sine, cosine and random numbers
// for the scene generators; "det" is "deterministic", not "determinant"). Kept so that code written
// against the old name, tests/cullide/scenes_test.cpp among it, still compiles; include
// scene_math.h in new code.
#pragma once

#include "scene_math.h"
