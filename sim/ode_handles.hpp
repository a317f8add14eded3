// Ownership of ODE objects, and ODE's process-wide initialisation. Internal to rsca_sim.
#pragma once

#include <memory>

#include <ode/ode.h>

namespace rsca::sim::ode {

// Initialises ODE on first use (dInitODE2) and closes it at process exit (dCloseODE); also
// allocates ODE's per-thread collision data for the calling thread, once per thread. Call it
// before any other ODE call on a thread.
void ensure_ready_on_this_thread();

struct WorldDeleter {
  void operator()(dxWorld *id) const { dWorldDestroy(id); }
};
struct SpaceDeleter {
  void operator()(dxSpace *id) const { dSpaceDestroy(id); }
};
struct GeomDeleter {
  void operator()(dxGeom *id) const { dGeomDestroy(id); }
};
struct BodyDeleter {
  void operator()(dxBody *id) const { dBodyDestroy(id); }
};
struct JointDeleter {
  void operator()(dxJoint *id) const { dJointDestroy(id); }
};
struct JointGroupDeleter {
  void operator()(dxJointGroup *id) const { dJointGroupDestroy(id); }
};

// Spaces are created without cleanup (dSpaceSetCleanup 0) so that their geoms keep a single
// owner. Bodies and joints must go before their world: declare the world handle first.
using World = std::unique_ptr<dxWorld, WorldDeleter>;
using Space = std::unique_ptr<dxSpace, SpaceDeleter>;
using Geom = std::unique_ptr<dxGeom, GeomDeleter>;
using Body = std::unique_ptr<dxBody, BodyDeleter>;
using Joint = std::unique_ptr<dxJoint, JointDeleter>;
using JointGroup = std::unique_ptr<dxJointGroup, JointGroupDeleter>;

} // namespace rsca::sim::ode
