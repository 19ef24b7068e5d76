// The viewer's simulation: each of Witkin's interactions applied to a real
// system, checked against the physics it should produce, and the controls
// (real-time stepping, solver and dt, reset, reload) with their refusals.
#include "session.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "support/test_support.hpp"

namespace pdyn::viewer {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::unique_ptr<Session> session_for(const std::string& name, const std::string& yaml) {
  const fs::path file = test::write_file(test::temp_dir("viewer-" + name) / "scene.yaml", yaml);
  SessionOptions o;
  o.scene = file;
  o.plugin_path = {PDYN_PLUGIN_DIR};
  return std::make_unique<Session>(std::move(o));
}

Command cmd(const std::string& text) { return parse_command(text); }

std::string refusal(Session& s, const std::string& text, int client = 1) {
  try {
    s.apply(cmd(text), client);
  } catch (const CommandError& e) {
    return e.what();
  }
  return "accepted";
}

void steps(Session& s, int n) {
  for (int k = 0; k < n; ++k) s.apply(cmd(R"({"op":"step"})"), 0);
}

Vec3 x(const Session& s, Index i) { return s.system().positions().col(i); }

// One free particle of 1 kg at the origin, no forces: only the mouse spring acts.
const char* kLone = R"(
simulation: { dt: 0.001, steps: 10, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 0], mass: 1 }
  - { position: [0, 0, 5], mass: 1 }
)";

TEST(ViewerSession, DragPullsTheParticleTowardTheCursorAndReleaseRemovesTheSpring) {
  auto s = session_for("drag", kLone);
  const std::size_t forces = s->system().force_objects().size();
  s->apply(cmd(R"({"op":"drag","id":0,"point":[1,0,0]})"), 1);
  EXPECT_EQ(s->system().force_objects().size(), forces + 1);
  // Default: ks = M (2 pi 1.5 Hz)^2 with M = 2 kg, critically damped for
  // the 1 kg particle: an overdamped-free approach x(t) = 1 - (1 + wt) e^{-wt}.
  const auto [ks, kd] = s->default_mouse_spring(0);
  const double w = std::sqrt(ks);
  EXPECT_NEAR(ks, 2.0 * std::pow(2 * M_PI * 1.5, 2), 1e-9);
  EXPECT_NEAR(kd, 2.0 * w, 1e-9);
  steps(*s, 200);
  const double t = 0.2;
  EXPECT_NEAR(x(*s, 0).x(), 1.0 - (1.0 + w * t) * std::exp(-w * t), 1e-8);
  EXPECT_EQ(x(*s, 0).y(), 0.0);
  // Moving the cursor moves the target.
  s->apply(cmd(R"({"op":"move","point":[1,2,0]})"), 1);
  const double y0 = x(*s, 0).y();
  steps(*s, 100);
  EXPECT_GT(x(*s, 0).y(), y0 + 0.5);
  s->apply(cmd(R"({"op":"release"})"), 1);
  EXPECT_EQ(s->system().force_objects().size(), forces);
  // Released: the particle coasts at constant velocity.
  const Vec3 v = s->system().velocities().col(0);
  const Vec3 before = x(*s, 0);
  steps(*s, 10);
  EXPECT_NEAR((x(*s, 0) - before - 0.01 * v).norm(), 0.0, 1e-12);
}

TEST(ViewerSession, EachClientHasItsOwnMouseSpringAndLosesItWhenItLeaves) {
  auto s = session_for("two", kLone);
  const std::size_t forces = s->system().force_objects().size();
  s->apply(cmd(R"({"op":"drag","id":0,"point":[1,0,0]})"), 1);
  s->apply(cmd(R"({"op":"drag","id":1,"point":[0,0,6]})"), 2);
  s->apply(cmd(R"({"op":"drag","id":1,"point":[0,0,4]})"), 2);  // replaces client 2's spring
  EXPECT_EQ(s->system().force_objects().size(), forces + 2);
  steps(*s, 100);
  EXPECT_GT(x(*s, 0).x(), 0.1);
  EXPECT_LT(x(*s, 1).z(), 4.9);
  s->forget_client(2);
  EXPECT_EQ(s->system().force_objects().size(), forces + 1);
  s->forget_client(2);  // twice is harmless
  s->apply(cmd(R"({"op":"release"})"), 1);
  EXPECT_EQ(s->system().force_objects().size(), forces);
}

const char* kFalling = R"(
simulation: { dt: 0.001, steps: 10, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 1], mass: 0.5 }
  - { position: [1, 0, 1], mass: 0.5 }
forces:
  - { type: gravity, g: [0, 0, -10] }
)";

TEST(ViewerSession, NailHoldsAParticleStillAndTogglesBack) {
  auto s = session_for("nail", kFalling);
  steps(*s, 100);
  const std::uint32_t topology = s->topology();
  s->apply(cmd(R"({"op":"nail","id":0})"), 1);
  EXPECT_EQ(s->topology(), topology + 1);
  EXPECT_TRUE(s->system().fixed()[0]);
  const Vec3 held = x(*s, 0);
  EXPECT_EQ(s->system().velocities().col(0), Vec3::Zero());
  steps(*s, 300);
  EXPECT_EQ(x(*s, 0), held);                // bit for bit
  EXPECT_LT(x(*s, 1).z(), held.z() - 0.3);  // the other one keeps falling
  s->apply(cmd(R"({"op":"nail","id":0})"), 1);
  EXPECT_FALSE(s->system().fixed()[0]);
  steps(*s, 100);  // free again, from rest: falls g t^2 / 2 = 0.05 m in 0.1 s
  EXPECT_NEAR(x(*s, 0).z(), held.z() - 0.05, 1e-12);
}

TEST(ViewerSession, CreateAddsAParticleThatTheScenesForcesAct) {
  auto s = session_for("create", kFalling);
  const auto id = s->apply(cmd(R"({"op":"create","point":[2,0,3],"mass":0.25})"), 1);
  ASSERT_TRUE(id);
  EXPECT_EQ(*id, 2);
  EXPECT_EQ(s->system().size(), 3);
  EXPECT_EQ(s->system().masses()(2), 0.25);
  EXPECT_EQ(x(*s, 2), Vec3(2, 0, 3));
  EXPECT_EQ(json::parse(s->scene_json())["count"], 3);
  steps(*s, 200);  // gravity acts on every particle, the new one too
  EXPECT_NEAR(x(*s, 2).z(), 3.0 - 0.5 * 10 * 0.2 * 0.2, 1e-12);
}

// The scene message carries the radii (null when the scene gives none) and
// the simulation box (null in open space); a created particle gets radius 0,
// and a periodic box wraps the viewer's steps as it does a run's.
TEST(ViewerSession, SceneMessageHasRadiiAndTheBox) {
  auto s = session_for("radius-box", R"(
simulation:
  dt: 0.01
  steps: 10
  solver: { type: euler }
  box: { min: [0, 0, 0], max: [1, 2, 3], periodic: [true, false, false] }
particles:
  - { position: [0.95, 1, 1], velocity: [10, 0, 0], mass: 1, radius: 0.1 }
  - { position: [0.5, 1, 1], mass: 1 }
)");
  json scene = json::parse(s->scene_json());
  EXPECT_EQ(scene["radius"], json::array({0.1, 0.0}));
  EXPECT_EQ(scene["box"]["min"], json::array({0.0, 0.0, 0.0}));
  EXPECT_EQ(scene["box"]["max"], json::array({1.0, 2.0, 3.0}));
  EXPECT_EQ(scene["box"]["periodic"], json::array({true, false, false}));
  s->apply(cmd(R"({"op":"create","point":[0.5,0.5,0.5],"mass":1})"), 1);
  scene = json::parse(s->scene_json());
  EXPECT_EQ(scene["radius"], json::array({0.1, 0.0, 0.0}));
  steps(*s, 1);  // 0.95 + 0.1 m: across x = 1, back in at 0.05
  EXPECT_NEAR(x(*s, 0).x(), 0.05, 1e-12);
  EXPECT_EQ(s->system().images()[0][0], 1);

  auto open = session_for("no-radius-box", kLone);
  scene = json::parse(open->scene_json());
  EXPECT_TRUE(scene["radius"].is_null());
  EXPECT_TRUE(scene["box"].is_null());
}

TEST(ViewerSession, AttachAddsASpringAtRestAtTheCurrentDistance) {
  // A nailed particle and a hanging one 0.5 m below, attached: the spring
  // starts at rest, so the hanging one settles mg/ks below it, with its
  // damping: 0.1 kg, ks 100 N/m, kd 1 N s/m (damping time 2m/kd = 0.2 s).
  auto s = session_for("attach", R"(
simulation: { dt: 0.001, steps: 10, solver: { type: rk4 } }
particles:
  - { position: [0, 0, 1], mass: 1, fixed: true }
  - { position: [0, 0, 0.5], mass: 0.1 }
forces:
  - { type: gravity, g: [0, 0, -9.81] }
)");
  const auto links = json::parse(s->scene_json())["links"].size();
  s->apply(cmd(R"({"op":"attach","a":0,"b":1,"ks":100,"kd":1})"), 1);
  const json scene = json::parse(s->scene_json());
  ASSERT_EQ(scene["links"].size(), links + 1);
  EXPECT_EQ(scene["links"].back(), json::array({0, 1}));
  steps(*s, 4000);  // 4 s: 20 damping times
  EXPECT_NEAR(x(*s, 1).z(), 0.5 - 0.1 * 9.81 / 100, 1e-6);
  EXPECT_EQ(refusal(*s, R"({"op":"attach","a":1,"b":1})"),
            "attach: fields 'a' and 'b' are both particle 1 (expected two different particles)");
  EXPECT_EQ(refusal(*s, R"({"op":"attach","a":0,"b":2})"),
            "attach: field 'b' is 2, but there are 2 particles (expected 0..1)");
}

TEST(ViewerSession, RefusedCommandsSayWhyAndChangeNothing) {
  auto s = session_for("refused", kFalling);
  const std::size_t forces = s->system().force_objects().size();
  EXPECT_EQ(refusal(*s, R"({"op":"drag","id":5,"point":[0,0,0]})"),
            "drag: field 'id' is 5, but there are 2 particles (expected 0..1)");
  EXPECT_EQ(refusal(*s, R"({"op":"nail","id":2})"),
            "nail: field 'id' is 2, but there are 2 particles (expected 0..1)");
  const std::string solver = refusal(*s, R"({"op":"solver","name":"rk5"})");
  EXPECT_EQ(solver.rfind("solver: there is no solver plugin 'rk5' (expected one of: ", 0), 0u)
      << solver;
  EXPECT_NE(solver.find("rk4"), std::string::npos);
  EXPECT_EQ(s->system().force_objects().size(), forces);
  EXPECT_EQ(s->solver_name(), "rk4");
  // Moving or releasing without a mouse spring does nothing.
  EXPECT_EQ(refusal(*s, R"({"op":"move","point":[0,0,0]})"), "accepted");
  EXPECT_EQ(refusal(*s, R"({"op":"release"})"), "accepted");
}

TEST(ViewerSession, AdvanceKeepsRealTimeTimesTheSpeedAndDropsWhatItCannotCatchUp) {
  auto s = session_for("realtime", kFalling);
  s->advance(0.1, 10.0);
  EXPECT_EQ(s->steps(), 0u);  // paused
  s->apply(cmd(R"({"op":"play"})"), 1);
  s->advance(0.1, 10.0);  // 0.1 s of wall time at dt 1 ms: 100 steps
  EXPECT_EQ(s->steps(), 100u);
  s->apply(cmd(R"({"op":"speed","value":2})"), 1);
  s->advance(0.05, 10.0);
  EXPECT_EQ(s->steps(), 200u);
  s->apply(cmd(R"({"op":"dt","value":0.01})"), 1);
  s->advance(0.05, 10.0);
  EXPECT_EQ(s->steps(), 210u);
  EXPECT_NEAR(s->system().time(), 0.3, 1e-12);
  // No budget: one step, and the rest of the owed time is dropped.
  s->advance(10.0, 0.0);
  EXPECT_EQ(s->steps(), 211u);
  s->advance(0.0, 10.0);
  EXPECT_LE(s->steps(), 212u);
  s->apply(cmd(R"({"op":"pause"})"), 1);
  s->advance(1.0, 10.0);
  EXPECT_LE(s->steps(), 212u);
}

TEST(ViewerSession, SolverAndDtChangeLiveAndResetStartsOver) {
  auto s = session_for("solver", kFalling);
  s->apply(cmd(R"({"op":"solver","name":"symplectic_euler"})"), 1);
  EXPECT_EQ(s->solver_name(), "symplectic_euler");
  EXPECT_EQ(json::parse(s->status_json())["solver"], "symplectic_euler");
  s->apply(cmd(R"({"op":"dt","value":0.002})"), 1);
  steps(*s, 50);
  EXPECT_NEAR(s->system().time(), 0.1, 1e-12);
  s->apply(cmd(R"({"op":"create","point":[0,0,0],"mass":1})"), 1);
  const std::uint32_t topology = s->topology();
  s->apply(cmd(R"({"op":"reset"})"), 1);
  EXPECT_GT(s->topology(), topology);
  EXPECT_EQ(s->system().size(), 2);
  EXPECT_EQ(s->steps(), 0u);
  EXPECT_EQ(s->system().time(), 0.0);
  EXPECT_EQ(x(*s, 0), Vec3(0, 0, 1));
  EXPECT_EQ(s->solver_name(), "rk4");  // the scene's own
  EXPECT_EQ(s->dt(), 0.001);
}

TEST(ViewerSession, ReloadReadsTheFileAgainAndABrokenSceneKeepsTheRunningOne) {
  const fs::path dir = test::temp_dir("viewer-reload");
  const fs::path file = test::write_file(dir / "scene.yaml", kFalling);
  SessionOptions o;
  o.scene = file;
  o.plugin_path = {PDYN_PLUGIN_DIR};
  Session s(std::move(o));
  steps(s, 10);
  test::write_file(
      file,
      "simulation: { dt: 0.001, steps: 10 }\nparticles:\n  - { position: [0, 0], mass: 1 }\n");
  const std::string e = refusal(s, R"({"op":"reload"})");
  EXPECT_EQ(e.rfind("reload: the scene has errors; the running simulation is kept\n", 0), 0u) << e;
  EXPECT_NE(e.find(file.string() + ":3:"), std::string::npos) << e;  // FILE:LINE:COLUMN
  EXPECT_EQ(s.steps(), 10u);
  EXPECT_EQ(s.system().size(), 2);
  steps(s, 1);
  EXPECT_EQ(s.steps(), 11u);
  test::write_file(file, std::string(kFalling) + "  - { type: drag, k: 0.1 }\n");
  s.apply(cmd(R"({"op":"reload"})"), 1);
  EXPECT_EQ(s.steps(), 0u);
  EXPECT_EQ(s.system().force_objects().size(), 2u);
}

TEST(ViewerSession, ABlowUpPausesOnTheLastGoodStateWithAMessage) {
  auto s = session_for("blowup", R"(
simulation: { dt: 0.1, steps: 10, solver: { type: euler } }
particles:
  - { position: [0, 0, 0], mass: 0.001, fixed: true }
  - { position: [1, 0, 0], mass: 0.001 }
forces:
  - { type: spring, pairs: [[0, 1]], ks: 1.0e6, rest: [0.5] }
)");
  s->apply(cmd(R"({"op":"play"})"), 1);
  for (int k = 0; k < 200 && s->playing(); ++k) s->advance(0.1, 10.0);
  EXPECT_FALSE(s->playing());
  EXPECT_TRUE(s->system().state().allFinite());
  const json status = json::parse(s->status_json());
  ASSERT_TRUE(status["message"].is_string());
  EXPECT_NE(status["message"].get<std::string>().find("became non-finite"), std::string::npos);
}

std::unique_ptr<Session> session_for_config(const std::string& name) {
  SessionOptions o;
  o.scene = test::source_path("configs/" + name);
  o.plugin_path = {PDYN_PLUGIN_DIR};
  return std::make_unique<Session>(std::move(o));
}

// The scene message lists each constraint object with its rows' particles,
// in the kernel's order: the double pendulum's two rods (pivot-bob 1, bob
// 1-bob 2) and the bead's two rows on its one particle (in the wire's plane,
// on the circle). Its status carries max |C|; a scene without constraints
// has none and a null error.
TEST(ViewerSession, SceneMessageListsTheConstraintRows) {
  auto pendulum = session_for_config("double_pendulum.yaml");
  json scene = json::parse(pendulum->scene_json());
  ASSERT_EQ(scene["constraints"].size(), 1u);
  const json& rods = scene["constraints"][0];
  EXPECT_EQ(rods["type"], "distance");
  EXPECT_EQ(rods["label"].get<std::string>().rfind("distance (", 0), 0u) << rods["label"];
  EXPECT_EQ(rods["rows"], json::array({json::array({0, 1}), json::array({1, 2})}));
  EXPECT_EQ(scene["links"], json::array());  // rods are not springs
  // Written at the initial state the constraints were made from: C = 0.
  EXPECT_LT(json::parse(pendulum->status_json())["constraint_error"].get<double>(), 1e-15);

  auto bead = session_for_config("bead_on_wire.yaml");
  scene = json::parse(bead->scene_json());
  ASSERT_EQ(scene["constraints"].size(), 1u);
  EXPECT_EQ(scene["constraints"][0]["type"], "on_circle");
  EXPECT_EQ(scene["constraints"][0]["rows"], json::array({json::array({0}), json::array({0})}));

  auto free = session_for("no-constraints", kLone);
  EXPECT_EQ(json::parse(free->scene_json())["constraints"], json::array());
  EXPECT_TRUE(json::parse(free->status_json())["constraint_error"].is_null());
}

// Dragging a constrained particle, as the page does: the mouse spring is one
// more applied force, and Witkin's constraint force resists it along the
// constrained directions. The bead (configs/bead_on_wire.yaml: 0.1 kg on a
// vertical circle of radius 1 m about the origin, in the plane y = 0,
// starting at theta = 120 degrees from the bottom) is grabbed where it is
// and the cursor moved to T = (-0.5, 0.4, 2), off the wire and 0.4 m out of
// its plane, beyond the top. On the circle, p = (sin t, 0, -cos t), the
// bead's energy with the spring (stiffness ks) is
//   U(t) = m g z + ks |p - T|^2 / 2 = A cos t + B sin t + const,
//   A = ks Tz - m g,  B = -ks Tx,
// least at t* = atan2(B, A) + pi: over the top, about 195 degrees. The bead
// must slide along the wire there and stay on it every step.
TEST(ViewerSession, DraggingABeadOnAWireMovesItAlongTheWireAndKeepsItOnIt) {
  auto s = session_for_config("bead_on_wire.yaml");
  ASSERT_EQ(s->solver_name(), "rk4");
  const Vec3 start = x(*s, 0);
  const double theta0 = std::atan2(start.x(), -start.z());
  ASSERT_NEAR(theta0, 2 * M_PI / 3, 1e-12);
  s->apply(
      cmd(json{{"op", "drag"}, {"id", 0}, {"point", {start.x(), start.y(), start.z()}}}.dump()), 1);
  const Vec3 target(-0.5, 0.4, 2.0);
  s->apply(cmd(R"({"op":"move","point":[-0.5,0.4,2.0]})"), 1);

  const double m = 0.1, g = 9.81;
  const double ks = s->default_mouse_spring(0).first;
  const double expected = std::atan2(-ks * target.x(), ks * target.z() - m * g) + M_PI;
  ASSERT_NEAR(expected * 180 / M_PI, 194.8, 0.1);  // the set-up is what the comment says

  // The angle unwrapped across the top (atan2 jumps from pi to -pi there).
  double theta = theta0, max_error = 0.0, max_off_wire = 0.0;
  const double d0 = (start - target).norm();
  for (int k = 0; k < 3000; ++k) {  // 3 s; the spring's damping time 2 m / kd is 0.1 s
    steps(*s, 1);
    const Vec3 p = x(*s, 0);
    const double a = std::atan2(p.x(), -p.z());
    theta += std::remainder(a - theta, 2 * M_PI);
    max_error = std::max(max_error, s->system().constraint_error());
    max_off_wire = std::max({max_off_wire, std::abs(p.y()), std::abs(p.norm() - 1.0)});
    if (k == 99) {
      // (a) After 0.1 s it is already on its way up toward the cursor,
      // not falling back to the bottom as it would alone.
      EXPECT_GT(theta, theta0 + 0.2) << "theta " << theta * 180 / M_PI << " degrees";
    }
  }
  // (a) Along the wire to where the spring's pull balances gravity's.
  EXPECT_GT(theta, theta0 + M_PI / 3) << "moved " << (theta - theta0) * 180 / M_PI << " degrees";
  EXPECT_NEAR(theta, expected, 1e-3);
  // From 2.07 m to 1.13 m of the cursor: the wire comes no nearer than
  // sqrt((|(Tx, Tz)| - 1)^2 + Ty^2) = 1.1346 m.
  EXPECT_LT((x(*s, 0) - target).norm(), d0 - 0.9);
  // (b) And on it every step, against a spring pulling it 0.4 m out of the
  // wire's plane: the kernel's max |C| and the geometry alike.
  EXPECT_LT(max_error, 1e-6);
  EXPECT_LT(max_off_wire, 1e-6);
  const json status = json::parse(s->status_json());
  EXPECT_EQ(status["constraint_error"].get<double>(), s->system().constraint_error());
  std::cout << "bead dragged from " << theta0 * 180 / M_PI << " to " << theta * 180 / M_PI
            << " degrees (rest at " << expected * 180 / M_PI << "); max |C| " << max_error
            << " m, max off the wire " << max_off_wire << " m\n";

  // Released, it swings under gravity alone, still on the wire.
  s->apply(cmd(R"({"op":"release"})"), 1);
  const double before = theta;
  for (int k = 0; k < 500; ++k) {
    steps(*s, 1);
    const Vec3 p = x(*s, 0);
    theta += std::remainder(std::atan2(p.x(), -p.z()) - theta, 2 * M_PI);
    max_error = std::max(max_error, s->system().constraint_error());
  }
  // Down the far side, toward the bottom at 360 degrees: from 15 degrees
  // past the top and at rest, more than 10 degrees in 0.5 s.
  EXPECT_GT(theta, before + 0.2);
  EXPECT_LT(max_error, 1e-6);
}

TEST(ViewerSession, StateJsonListsEveryParticle) {
  auto s = session_for("state", kFalling);
  const json j = json::parse(s->state_json());
  EXPECT_EQ(j["count"], 2);
  EXPECT_EQ(j["step"], 0);
  EXPECT_EQ(j["particles"][1]["x"], json::array({1.0, 0.0, 1.0}));
  EXPECT_EQ(j["particles"][1]["mass"], 0.5);
  EXPECT_EQ(j["particles"][1]["fixed"], false);
  const Frame f = s->frame();
  EXPECT_EQ(f.positions.size(), 6u);
  EXPECT_EQ(f.positions[3], 1.0f);
  EXPECT_NEAR(f.potential, 2 * 0.5 * 10 * 1, 1e-12);  // m g z for both
  EXPECT_EQ(json::parse(s->scene_json())["flat"],
            "xy");  // z = 1 and v = 0 for all (y = 0 too: xy is tried first)
}

}  // namespace
}  // namespace pdyn::viewer
