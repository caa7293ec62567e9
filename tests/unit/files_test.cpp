// Files vibro writes (docs/reliability.md, "One writer per file"): the lock of an output file and
// the refusal of a second writer in the same process (two Python threads), and the scene bound
// that keeps a subnormal mass out.
#include <unistd.h>

#include <cstdio>
#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "io/file_lock.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"

namespace {

std::string TempPath(const char* name) {
  return ::testing::TempDir() + "vibro_files_test_" + std::to_string(getpid()) + "_" + name;
}

std::string Thrown(const std::function<void()>& f) {
  try {
    f();
  } catch (const vibro::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(FileLock, ASecondOpenInTheSameProcessIsRefusedNamingIt) {
  const std::string path = TempPath("lock.h5");
  bool created = false;
  {
    auto first = vibro::store::FileLock::Acquire(path, true, &created);
    ASSERT_TRUE(first.held());
    EXPECT_TRUE(created);
    const std::string why = Thrown([&] { vibro::store::FileLock::Acquire(path, false); });
    EXPECT_NE(why.find(path + " is in use by this process (" + std::to_string(getpid()) + ")"), std::string::npos)
        << why;
  }
  // Released with its holder: the next writer gets it.
  EXPECT_TRUE(vibro::store::FileLock::Acquire(path, false).held());
  std::remove(path.c_str());
}

TEST(FileLock, NoLockOnWhatIsNotARegularFile) {
  EXPECT_FALSE(vibro::store::FileLock::Acquire("/dev/null", false).held());
  EXPECT_FALSE(vibro::store::FileLock::Acquire(::testing::TempDir(), false).held());
}

TEST(FileLock, TwoStoresOfOneFileInOneProcess) {
  // Two Python threads writing one file: the second is refused, the first's file stays whole.
  const std::string path = TempPath("store.h5");
  const auto scene = vibro::LoadScene(std::string(VIBRO_SCENES_DIR) + "/default.toml");
  vibro::StoreHeader h;
  h.scene_text = scene.text_as_run;
  h.engine = "exact";
  h.dof = 1;
  h.command = "simulate";
  h.frequencies = h.forcing = h.contact = h.contact_shape = h.damping_ratios = Eigen::VectorXd::Ones(1);
  auto first = vibro::Hdf5Store::Create(path, h);
  const std::string why = Thrown([&] { vibro::Hdf5Store::Create(path, h); });
  EXPECT_NE(why.find("is in use by this process"), std::string::npos) << why;
  vibro::RunResult r;
  first->Finish(r, vibro::Attractor{});
  first.reset();
  EXPECT_EQ(vibro::ReadStoredRun(path).status, "ok");
  std::remove(path.c_str());
}

TEST(SceneBounds, SubnormalMassIsBadInput) {
  const std::string text =
      "[structure]\nmass = [[5e-324]]\nstiffness = [[1.0]]\nforcing_dof = 0\ncontact_dof = 0\n"
      "[stop]\nposition = 1.0\nrestitution = 0.5\n[excitation]\namplitude = 1.0\nfrequency = 2.0\n";
  const std::string why = Thrown([&] { vibro::ParseScene(text, "subnormal.toml"); });
  EXPECT_NE(why.find("structure.mass"), std::string::npos) << why;
}

}  // namespace
