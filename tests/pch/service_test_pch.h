// Precompiled for the in-process service tests (tests/service): the test
// headers above plus the server's own stack (vpm_server.h reaches the
// sessions, stores, scene, FEM and GPU context), which alone costs a unity
// batch about 20 s of parsing.
#pragma once

#include "tests/pch/test_pch.h"
#include "tests/service/service_test_util.h"
