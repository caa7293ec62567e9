// Scene files: every constraint rejected with a located message, overrides, round trip.
#include "vibro/scene_file.hpp"

#include <filesystem>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace vibro {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr const char* kModal = R"(title = "base"
[structure]
frequencies = [1.0, 2.5]
forcing = [1.0, 0.5]
contact = [1.0, 0.8]
[stop]
position = 1.0
restitution = 0.75
[excitation]
amplitude = 1.2
frequency = 2.8
)";

constexpr const char* kPhysical = R"([structure]
mass = [[1.0, 0.0], [0.0, 1.0]]
stiffness = [[2.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
contact_dof = 1
[stop]
position = 1.0
restitution = 0.5
[excitation]
amplitude = 1.5
frequency = 1.2
)";

std::vector<std::string> Problems(const std::string& text, const std::vector<std::string>& sets) {
  try {
    ParseScene(text, "scene.toml", sets);
  } catch (const InputError& e) {
    return e.messages();
  }
  return {};
}

// One override breaks one constraint: exactly one message, naming key and constraint.
void ExpectRejected(const char* base, const std::string& set, const std::string& key,
                    const std::string& constraint) {
  const auto problems = Problems(base, {set});
  SCOPED_TRACE(set);
  ASSERT_EQ(problems.size(), 1u) << (problems.empty() ? "accepted" : problems.front());
  EXPECT_THAT(problems[0], AllOf(HasSubstr(key), HasSubstr(constraint)));
  EXPECT_THAT(problems[0], HasSubstr("--set " + set));
}

TEST(SceneFile, ValidScenesParse) {
  const auto m = ParseScene(kModal, "scene.toml");
  ASSERT_TRUE(m.scene.modal);
  EXPECT_EQ(m.scene.modal->frequencies.size(), 2);
  EXPECT_EQ(m.scene.run.engine, Engine::kExact);
  EXPECT_EQ(m.scene.run.chatter, ChatterTreatment::kAccumulation);
  const auto p = ParseScene(kPhysical, "scene.toml");
  ASSERT_TRUE(p.scene.physical);
  EXPECT_EQ(p.scene.physical->contact_dof, 1);
}

TEST(SceneFile, EveryConstraintIsRejected) {
  ExpectRejected(kModal, "stop.restitution=1.5", "stop.restitution", "0 ≤ r ≤ 1");
  ExpectRejected(kModal, "stop.restitution=-0.1", "stop.restitution", "0 ≤ r ≤ 1");
  ExpectRejected(kModal, "excitation.frequency=0", "excitation.frequency", "ω > 0");
  ExpectRejected(kModal, "excitation.amplitude=-1", "excitation.amplitude", "f ≥ 0");
  ExpectRejected(kModal, "excitation.amplitude=nan", "excitation.amplitude", "finite");
  ExpectRejected(kModal, "stop.position=inf", "stop.position", "finite");
  ExpectRejected(kModal, "structure.frequencies=[1.0, -2.0]", "structure.frequencies", "ω_i > 0");
  ExpectRejected(kModal, "structure.forcing=[1.0]", "structure.forcing", "length 2");
  ExpectRejected(kModal, "structure.contact=[1.0, 0.0]", "structure.contact", "physical form");
  ExpectRejected(kModal, "structure.damping_ratios=[0.1]", "structure.damping_ratios", "length 2");
  ExpectRejected(kModal, "structure.damping_ratios=[0.1, 1.2]", "structure.damping_ratios", "ζ_i < 1");
  ExpectRejected(kModal, "structure.modes=3", "structure.modes", "modes ≤ 2");
  ExpectRejected(kModal, "structure.frequencies=[1.0, nan]", "structure.frequencies", "finite");
  ExpectRejected(kModal, "run.periods=0", "run.periods", "periods ≥ 1");
  ExpectRejected(kModal, "run.rtol=0", "run.rtol", "1e-14 ≤ rtol");
  ExpectRejected(kModal, "run.rtol=1e-300", "run.rtol", "1e-14 ≤ rtol");
  ExpectRejected(kModal, "run.engine=\"euler\"", "run.engine", "\"exact\" | \"cvode\"");
  ExpectRejected(kModal, "run.chatter=\"skip\"", "run.chatter", "\"accumulation\"");
  ExpectRejected(kModal, "run.chatter_switch=2", "run.chatter_switch", "chatter_switch < 1");
  ExpectRejected(kModal, "run.samples_per_period=-1", "run.samples_per_period", "≥ 0");
  ExpectRejected(kModal, "run.periods=2.5", "run.periods", "whole number");
  // Absolute times of 9.2e18 had an ulp of 2048: the written section times stopped increasing.
  ExpectRejected(kModal, "initial.time=9223372036854775807", "initial.time", "≤ 1e12");
  ExpectRejected(kModal, "run.periods=100000000000", "run.periods", "≤ 1e12");
  ExpectRejected(kPhysical, "structure.mass=[[1.0, 0.0], [0.0, -1.0]]", "structure.mass",
                 "positive definite");
  ExpectRejected(kPhysical, "structure.stiffness=[[2.0, -1.0], [-0.5, 1.0]]",
                 "structure.stiffness", "symmetric");
  ExpectRejected(kPhysical, "structure.stiffness=[[1.0, -1.0], [-1.0, 1.0]]",
                 "structure.stiffness", "positive definite");
  ExpectRejected(kPhysical, "structure.stiffness=[[2.0, -1.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
                 "structure.stiffness", "same size");
  ExpectRejected(kPhysical, "structure.contact_dof=2", "structure.contact_dof", "[0, 2)");
  ExpectRejected(kPhysical, "structure.forcing_dof=-1", "structure.forcing_dof", "[0, 2)");
  ExpectRejected(kPhysical, "structure.mass=[[1.0, 0.0], [0.0]]", "structure.mass", "equal length");
}

// A [[contact]] table's DOF out of range: one located line about contact[0].dof, and none about
// structure.contact_dof, a key the scene does not have (issue 38).
TEST(SceneFile, ContactDofOutOfRangeIsReportedOnceWhereItIsWritten) {
  const std::string text = R"([structure]
mass = [[1.0, 0.0], [0.0, 1.0]]
stiffness = [[2.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
[[contact]]
dof = 2
side = "above"
position = 1.0
restitution = 0.5
[excitation]
amplitude = 1.5
frequency = 1.2
)";
  const auto problems = Problems(text, {});
  ASSERT_EQ(problems.size(), 1u) << (problems.empty() ? "accepted" : problems.front() + " / " + problems.back());
  EXPECT_THAT(problems[0], AllOf(HasSubstr("scene.toml:6"), HasSubstr("contact[0].dof"), HasSubstr("[0, 2)")));
  EXPECT_THAT(problems[0], ::testing::Not(HasSubstr("contact_dof")));
}

TEST(SceneFile, InitialStateMustBeAdmissible) {
  // x_B = 1ᵀX = 0.9 < x0 = 1: inside the stop.
  auto p = Problems(kModal, {"initial.displacement=[0.5, 0.4]", "initial.velocity=[0.0, 0.0]"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], AllOf(HasSubstr("initial.displacement"), HasSubstr("x_B ≥ x0")));
  // On the stop, moving into it.
  p = Problems(kModal, {"initial.displacement=[0.5, 0.5]", "initial.velocity=[-1.0, 0.5]"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], AllOf(HasSubstr("initial.velocity"), HasSubstr("into it")));
  // Physical form: q_B = 2 ≥ 1 is fine.
  EXPECT_TRUE(Problems(kPhysical, {"initial.displacement=[0.0, 2.0]", "initial.velocity=[0.0, 0.0]"})
                  .empty());
  p = Problems(kModal, {"initial.displacement=[0.5, 0.7]", "initial.velocity=[0.0]"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("length 2"));
  p = Problems(kModal, {"initial.displacement=[0.5, 0.7]"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("give both"));
}

TEST(SceneFile, MessagesCarryFileLineAndColumn) {
  const std::string text = std::string(kModal) + "[run]\nrtol = -1.0\n";
  const auto p = Problems(text, {});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("scene.toml:13:8: run.rtol = -1.0: violated constraint 1e-14 ≤ rtol < 1"));
}

TEST(SceneFile, ThreeMistakesGiveThreeLocatedMessages) {
  const std::string text = R"([structure]
frequencies = [1.0]
forcing = [1.0]
contact = [1.0]
[stop]
position = 1.0
restitution = 1.5
[excitation]
amplitude = -2.0
frequency = 2.8
[run]
chater = "none"
)";
  const auto p = Problems(text, {});
  ASSERT_EQ(p.size(), 3u);
  EXPECT_THAT(p[0], HasSubstr("scene.toml:12:1: run.chater: unknown key; did you mean run.chatter?"));
  EXPECT_THAT(p[1], HasSubstr("scene.toml:7:15: stop.restitution = 1.5"));
  EXPECT_THAT(p[2], HasSubstr("scene.toml:9:13: excitation.amplitude = -2.0"));
}

TEST(SceneFile, UnknownKeysGetAHint) {
  auto p = Problems(std::string(kModal) + "[exitation]\namplitude = 1.0\n", {});
  ASSERT_GE(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("did you mean excitation?"));
  p = Problems(kModal, {"run.restitution=0.5"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("did you mean stop.restitution?"));
}

TEST(SceneFile, MissingKeysAndBothFormsAreReported) {
  auto p = Problems("[stop]\nposition = 1.0\nrestitution = 0.5\n", {});
  ASSERT_GE(p.size(), 2u);
  EXPECT_THAT(p[0], HasSubstr("missing required table [structure]"));
  EXPECT_THAT(p[1], HasSubstr("excitation.amplitude: missing required key"));
  p = Problems(kModal, {"structure.mass=[[1.0]]"});
  ASSERT_GE(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("not both"));
}

TEST(SceneFile, BadTomlAndBadOverride) {
  auto p = Problems("[structure\nfrequencies = [1.0]\n", {});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("scene.toml:1:"));
  p = Problems(kModal, {"run.engine=exact"});  // unquoted string
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("not valid TOML"));
  p = Problems(kModal, {"noequals"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("KEY=VALUE"));
}

TEST(SceneFile, OverridesRoundTripThroughTheTextAsRun) {
  const std::vector<std::string> sets = {"excitation.amplitude=2.5", "run.engine=\"cvode\"",
                                         "structure.frequencies=[1.0, 3.2]",
                                         "initial.displacement=[1.0, 0.5]",
                                         "initial.velocity=[0.0, 0.1]", "run.periods=7"};
  const auto a = ParseScene(kModal, "scene.toml", sets);
  EXPECT_EQ(a.scene.amplitude, 2.5);
  EXPECT_EQ(a.scene.run.engine, Engine::kCvode);
  EXPECT_EQ(a.scene.modal->frequencies[1], 3.2);
  EXPECT_EQ(a.scene.run.periods, 7);
  // The text as run parses back to the same scene, without the overrides.
  const auto b = ParseScene(a.text_as_run, "as-run.toml");
  EXPECT_EQ(b.scene.amplitude, a.scene.amplitude);
  EXPECT_EQ(b.scene.frequency, a.scene.frequency);
  EXPECT_EQ(b.scene.run.engine, a.scene.run.engine);
  EXPECT_EQ(b.scene.run.periods, a.scene.run.periods);
  EXPECT_EQ(b.scene.modal->frequencies, a.scene.modal->frequencies);
  EXPECT_EQ(b.scene.initial_velocity, a.scene.initial_velocity);
  EXPECT_EQ(b.scene.title, "base");
  EXPECT_EQ(b.text_as_run, a.text_as_run);
}

// A chain of two masses with a stop below each, in [[contact]] tables (docs/contacts.md).
constexpr const char* kTwoContacts = R"([structure]
mass = [[1.0, 0.0], [0.0, 1.0]]
stiffness = [[2.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
[[contact]]
dof = 1
side = "below"
position = 1.0
restitution = 0.5
[[contact]]
dof = 0
side = "below"
position = 0.2
restitution = 0.7
[excitation]
amplitude = 1.5
frequency = 1.2
)";

TEST(SceneFile, ContactKeysAreOverridden) {
  // contact[i].KEY sets the key of the i-th [[contact]] table, and only that one.
  const auto a = ParseScene(kTwoContacts, "scene.toml",
                            {"contact[1].position=0.25", "contact[1].restitution=0.3", "contact[0].restitution=0"});
  ASSERT_EQ(a.scene.contacts.size(), 2u);
  EXPECT_EQ(a.scene.contacts[0].position, 1.0);
  EXPECT_EQ(a.scene.contacts[0].restitution, 0.0);
  EXPECT_EQ(a.scene.contacts[1].position, 0.25);
  EXPECT_EQ(a.scene.contacts[1].restitution, 0.3);
  EXPECT_EQ(a.scene.contacts[1].dof, 0);
  // The text as run holds the new values, and SceneNumber reads them back.
  EXPECT_EQ(ParseScene(a.text_as_run, "as-run.toml").scene.contacts[1].position, 0.25);
  EXPECT_EQ(SceneNumber(a.text_as_run, "contact[1].position"), 0.25);
  EXPECT_EQ(SceneNumber(a.text_as_run, "contact[0].restitution"), 0.0);
  // Non-numeric keys of a table take their TOML value.
  const auto b = ParseScene(kTwoContacts, "scene.toml", {"contact[1].side=\"above\"", "contact[1].position=3.0"});
  EXPECT_EQ(b.scene.contacts[1].side, Side::kAbove);
  // The [stop] shorthand is contact[0] (position and restitution).
  const auto c = ParseScene(kPhysical, "scene.toml", {"contact[0].position=1.25", "contact[0].restitution=0.125"});
  EXPECT_EQ(c.scene.stop_position, 1.25);
  EXPECT_EQ(c.scene.restitution, 0.125);
  EXPECT_EQ(SceneNumber(kPhysical, "contact[0].position"), 1.0);
  EXPECT_EQ(SceneNumber(kPhysical, "contact[0].restitution"), 0.5);
}

TEST(SceneFile, ModalComponentsOfAContactAreOverridden) {
  // contact[i].modal[k]: one modal component of contact i (the modal form, docs/contacts.md).
  const std::string path = std::string(VIBRO_SCENES_DIR) + "/contacts_chain2_modal.toml";
  const auto base = LoadScene(path);
  const auto a = LoadScene(path, {"contact[1].modal[0]=0.5"});
  ASSERT_EQ(a.scene.contacts.size(), 2u);
  EXPECT_EQ(a.scene.contacts[1].modal[0], 0.5);
  EXPECT_EQ(a.scene.contacts[1].modal[1], base.scene.contacts[1].modal[1]);
  EXPECT_EQ(SceneNumber(a.text_as_run, "contact[1].modal[0]"), 0.5);
  // Contact 0 has no modal components; an entry beyond the modes is refused.
  for (const char* bad : {"contact[0].modal[0]=0.5", "contact[1].modal[2]=0.5"}) {
    SCOPED_TRACE(bad);
    try {
      LoadScene(path, {bad});
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.messages().front(), AllOf(HasSubstr(bad), HasSubstr("no such entry")));
    }
  }
}

TEST(SceneFile, ContactKeysOfAMissingContactAreRefusedWithTheCount) {
  auto p = Problems(kTwoContacts, {"contact[2].position=1.0"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], AllOf(HasSubstr("--set contact[2].position=1.0"), HasSubstr("no contact 2"),
                          HasSubstr("the scene has 2 contacts"), HasSubstr("[0, 2)")));
  p = Problems(kPhysical, {"contact[1].restitution=0.5"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], AllOf(HasSubstr("contact[1].restitution"), HasSubstr("the scene has 1 contact"),
                          HasSubstr("[stop]")));
  // Each constraint of a contact, with its key.
  ExpectRejected(kTwoContacts, "contact[1].restitution=1.5", "contact[1].restitution", "0 ≤ r ≤ 1");
  ExpectRejected(kTwoContacts, "contact[0].restitution=-0.1", "contact[0].restitution", "0 ≤ r ≤ 1");
  // A misspelt key is named with the nearest key of the same table.
  p = Problems(kTwoContacts, {"contact[1].postion=1.0"});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], AllOf(HasSubstr("unknown key"), HasSubstr("contact[1].position?")));
  for (const char* bad : {"contact[x].position=1.0", "contact[-1].position=1.0", "contact[1]=1.0",
                          "contact[1].position[0]=1.0"}) {
    SCOPED_TRACE(bad);
    p = Problems(kTwoContacts, {bad});
    ASSERT_EQ(p.size(), 1u);
    EXPECT_THAT(p[0], HasSubstr(std::string("--set ") + bad));
  }
  // The [stop] of a one-contact scene has position and restitution only.
  p = Problems(kPhysical, {"contact[0].side=\"above\""});
  ASSERT_EQ(p.size(), 1u);
  EXPECT_THAT(p[0], HasSubstr("[stop] table"));
  // SceneNumber: a missing contact throws, naming the key and the count.
  try {
    SceneNumber(kTwoContacts, "contact[7].position");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.messages().front(), AllOf(HasSubstr("contact[7].position"), HasSubstr("2 contacts")));
  }
}

TEST(SceneFile, EveryShippedSceneLoads) {
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(VIBRO_SCENES_DIR)) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(LoadScene(entry.path().string()));
    ++count;
  }
  EXPECT_GE(count, 8);
}

}  // namespace
}  // namespace vibro
