/* THE C LAYER'S RULE (every C file of this folder): it marshals values (an FMI call's arguments to and from the
 * instance, the instance's arrays to and from the kernels, an FMU state to and from its blob), validates calls (the
 * call sequence, the pointers, every value a master sets or a state holds, by the library's rules as scene.h tables
 * them, refused in the library's words) and calls kernels (the library's numerics, compiled by numba: kernels.py,
 * network_kernels.py). It computes nothing of the model: every number of a step, an output, an energy, an
 * equilibrium or a stability check comes from a kernel. The only arithmetic here is the bookkeeping the library's
 * drivers do in Python around their kernels, in their order of operations: the clock (time = origin + steps * grid,
 * a duration split into whole steps) and the energy account's residual (work - dissipated - the change of kinetic
 * and stored energy). tests/fmu/native/test_refusals.py checks the refusals against the library's. */
/* The types of the kind this FMU is built for (scene.h says which: NETWORK, CONNECTOR): its Element, State and
 * Instance and the macros the shared headers read (element_types.h, connector_types.h, network_types.h). The services
 * below the kind's calls (core.h, calls.h, state.h) include this one; it includes common.h and the types alone. */
#ifndef PRANDTL_KIND_H
#define PRANDTL_KIND_H
#include "common.h"
#if NETWORK
#include "network_types.h"
#elif CONNECTOR
#include "connector_types.h"
#else
#include "element_types.h"
#endif

#endif
