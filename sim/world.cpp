#include "sim/world.hpp"

#include "sim/drive.hpp"
#include "sim/ode_handles.hpp"
#include "sim/range_sensor.hpp"
#include "sim/robot.hpp"

#include <array>
#include <cmath>
#include <mutex>
#include <optional>
#include <random>
#include <vector>

namespace rsca::sim {

namespace {

// Contact softness: stiff enough that a wheel sinks a few micrometres under the robot's
// weight, damped enough not to bounce at a 1 ms step.
constexpr double contact_erp = 0.2;
constexpr double contact_cfm = 1e-5;
constexpr int max_contacts = 4;
// Ground truth rays reach this far: beyond any room the experiment needs.
constexpr double true_range_length = 1000.0;

tl::unexpected<Error> sim_error(std::string rule, std::string message) {
  return make_error(SourceLocation{"sim", 0, 0}, std::move(rule), std::move(message));
}

} // namespace

struct World::Impl {
  explicit Impl(const Scenario &s)
      : scenario(s), world(dWorldCreate()), space(dSimpleSpaceCreate(nullptr)),
        contacts(dJointGroupCreate(0)), rng(s.seed) {
    dWorldSetGravity(world.get(), 0.0, 0.0, -gravity);
    // A simple space visits pairs in insertion order, which keeps contacts in the same order
    // from run to run.
    dSpaceSetCleanup(space.get(), 0);
    ground.reset(dCreatePlane(space.get(), 0.0, 0.0, 1.0, 0.0));
    for (const auto &spec : s.walls) {
      ode::Geom wall(dCreateBox(space.get(), spec.size.x(), spec.size.y(), spec.size.z()));
      dGeomSetPosition(wall.get(), spec.pose.position.x(), spec.pose.position.y(),
                       spec.size.z() / 2.0);
      dMatrix3 rotation;
      dRFromAxisAndAngle(rotation, 0.0, 0.0, 1.0, spec.pose.heading);
      dGeomSetRotation(wall.get(), rotation);
      wall_ids.push_back(wall.get());
      walls.push_back(std::move(wall));
    }
    robot.emplace(world.get(), space.get(), s.robot, s.start, s.initial_speed);
    commanded = Twist{s.initial_speed, 0.0};
    wheel_target = wheel_targets(s.robot, commanded);
    sensors.reserve(s.sensors.size());
    for (const auto &params : s.sensors)
      sensors.emplace_back(params);
    read_sensors();
    refresh_state();
  }

  // Called with the mutex held.
  void step() {
    if (estop_requested) {
      e_stopped = true;
      estop_requested = false;
      pending.reset();
      commanded = Twist{};
    }
    if (estop_reset_requested) {
      e_stopped = false;
      estop_reset_requested = false;
    }
    if (pending && !e_stopped)
      commanded = *pending;
    pending.reset();
    wheel_target = e_stopped ? WheelPair{} : wheel_targets(scenario.robot, commanded);
    robot->drive(wheel_target);

    dSpaceCollide(space.get(), this, &Impl::near_callback);
    dWorldStep(world.get(), scenario.time_step);
    dJointGroupEmpty(contacts.get());
    ++steps;
    read_sensors();
    refresh_state();
  }

  static void near_callback(void *data, dGeomID a, dGeomID b) {
    auto &self = *static_cast<Impl *>(data);
    dBodyID body_a = dGeomGetBody(a);
    dBodyID body_b = dGeomGetBody(b);
    if (!body_a && !body_b)
      return; // floor and walls
    // The chassis with its own caster, or a wheel with the chassis it is hinged to.
    if (body_a && body_b &&
        (body_a == body_b || dAreConnectedExcluding(body_a, body_b, dJointTypeContact)))
      return;
    std::array<dContact, max_contacts> found{};
    const int n = dCollide(a, b, max_contacts, &found[0].geom, sizeof(dContact));
    const bool slides = self.robot->is_caster(a) || self.robot->is_caster(b);
    for (int i = 0; i < n; ++i) {
      dContact &contact = found[static_cast<std::size_t>(i)];
      // Approx1 scales the friction limit with the normal force: mu is Coulomb's.
      contact.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM;
      contact.surface.mu = slides ? 0.0 : self.scenario.friction;
      contact.surface.soft_erp = contact_erp;
      contact.surface.soft_cfm = contact_cfm;
      dJointID joint = dJointCreateContact(self.world.get(), self.contacts.get(), &contact);
      dJointAttach(joint, body_a, body_b);
    }
  }

  double time() const { return static_cast<double>(steps) * scenario.time_step; }

  void read_sensors() {
    const Eigen::Isometry3d chassis = robot->chassis_pose();
    for (auto &sensor : sensors)
      sensor.update(time(), chassis, wall_ids, rng);
  }

  void refresh_state() {
    state.time = time();
    state.steps = steps;
    state.pose = Pose2::from_isometry(robot->chassis_pose());
    state.velocity = robot->velocity();
    state.commanded = commanded;
    state.wheel_speed = robot->wheel_speeds();
    state.wheel_target = wheel_target;
    state.e_stopped = e_stopped;
    state.ranges.resize(sensors.size());
    for (std::size_t i = 0; i < sensors.size(); ++i)
      state.ranges[i] = sensors[i].latest();
  }

  const Scenario scenario;
  mutable std::mutex mutex;
  // Teardown runs bottom-up: sensors and robot before the geoms' space, everything before the
  // world.
  ode::World world;
  ode::Space space;
  ode::JointGroup contacts;
  ode::Geom ground;
  std::vector<ode::Geom> walls;
  std::vector<dGeomID> wall_ids;
  std::optional<Robot> robot;
  std::vector<RangeSensor> sensors;
  std::mt19937_64 rng;

  std::uint64_t steps = 0;
  std::optional<Twist> pending;
  bool estop_requested = false;
  bool estop_reset_requested = false;
  bool e_stopped = false;
  Twist commanded;
  WheelPair wheel_target;
  WorldState state;
};

Expected<std::unique_ptr<World>> World::create(const Scenario &scenario) {
  if (auto valid = validate(scenario); !valid)
    return tl::unexpected<Error>(valid.error());
  ode::ensure_ready_on_this_thread();
  return std::make_unique<World>(Key{}, std::make_unique<Impl>(scenario));
}

World::World(Key /*only create*/, std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

World::~World() {
  ode::ensure_ready_on_this_thread();
}

void World::step() {
  ode::ensure_ready_on_this_thread();
  const std::lock_guard lock(impl_->mutex);
  impl_->step();
}

void World::advance(std::chrono::duration<double> duration) {
  const auto steps = std::llround(duration.count() / impl_->scenario.time_step);
  for (long long i = 0; i < steps; ++i)
    step();
}

Expected<Twist> World::set_velocity(double linear, double angular) {
  if (!std::isfinite(linear) || !std::isfinite(angular))
    return sim_error("sim-command", "velocity must be finite");
  const std::lock_guard lock(impl_->mutex);
  if (impl_->e_stopped || impl_->estop_requested)
    return sim_error("sim-e-stopped", "emergency stop is latched; reset it before driving");
  const auto &robot = impl_->scenario.robot;
  const Twist command = twist_of(robot, wheel_targets(robot, Twist{linear, angular}));
  impl_->pending = command;
  return command;
}

void World::emergency_stop() {
  const std::lock_guard lock(impl_->mutex);
  impl_->estop_requested = true;
  impl_->estop_reset_requested = false;
}

void World::reset_emergency_stop() {
  const std::lock_guard lock(impl_->mutex);
  // A stop still pending is applied first: the command it cleared stays cleared.
  if (impl_->e_stopped || impl_->estop_requested)
    impl_->estop_reset_requested = true;
}

WorldState World::snapshot() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->state;
}

Expected<double> World::true_range(std::size_t sensor) const {
  ode::ensure_ready_on_this_thread();
  const std::lock_guard lock(impl_->mutex);
  if (sensor >= impl_->sensors.size())
    return sim_error("sim-sensor", "no range sensor " + std::to_string(sensor));
  const auto hit =
      impl_->sensors[sensor].cast(impl_->robot->chassis_pose(), impl_->wall_ids, true_range_length);
  if (!hit)
    return sim_error("sim-no-wall", "no wall along the ray of range sensor \"" +
                                        impl_->sensors[sensor].params().name + "\"");
  return *hit;
}

const Scenario &World::scenario() const {
  return impl_->scenario;
}

double World::time_step() const {
  return impl_->scenario.time_step;
}

} // namespace rsca::sim
