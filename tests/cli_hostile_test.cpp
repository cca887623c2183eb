// Hostile command lines: every bad value of every option of render, reference and compare is
// refused before anything is loaded or rendered, with exit code 2, exactly one line on stderr
// that names the problem, and no file left behind. A hang is caught by run()'s time limit.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "cli_util.h"
#include "image/image_io.h"

namespace fs = std::filesystem;

namespace {

struct HostileCase {
  const char* args;                                      // after the binary, as for sh
  const char* expect;                                    // a substring of the one-line message
  std::function<void(const fs::path&)> setup = nullptr;  // fixtures in the run's folder
  bool needs_non_root = false;                           // permission bits do not stop root
};

void touch(const fs::path& p, const std::string& contents = "") { std::ofstream(p) << contents; }

const std::vector<HostileCase>& cases() {
  static const std::vector<HostileCase> table = {
      // --light-paths: CLI11 used to wrap -1 to 2^64-1 (segfault); the bound is 2^31-2.
      {"render cornell --spp 1 --light-paths -1", "--light-paths"},
      {"render cornell --spp 1 --light-paths 18446744073709551615", "--light-paths"},
      {"render cornell --spp 1 --light-paths 99999999999999999999999", "--light-paths"},
      {"render cornell --spp 1 --light-paths 2147483648", "--light-paths"},
      {"render cornell --spp 1 --light-paths 0", "--light-paths"},
      // Non-finite and out-of-range numbers (nan/inf used to hang the time budget).
      {"render cornell --time nan", "--time"},
      {"render cornell --time inf", "--time"},
      {"render cornell --time -1", "--time"},
      {"render cornell --time 1e30", "--time"},
      {"render cornell --spp 1 --radius nan", "--radius"},
      {"render cornell --spp 1 --radius -1", "--radius"},
      {"render cornell --spp 1 --radius-alpha nan", "--radius-alpha"},
      {"render cornell --spp 1 --radius-alpha 1e30", "--radius-alpha"},
      {"render cornell --spp 1 --radius-alpha 0", "--radius-alpha"},
      {"render cornell --spp 1 --exposure nan", "--exposure"},
      {"render cornell --spp 1 --exposure inf", "--exposure"},
      {"render cornell --spp 1 --max-depth -1", "--max-depth"},
      {"render cornell --spp 1 --max-depth -7", "--max-depth"},
      {"render cornell --spp 1 --max-depth 100000", "--max-depth"},
      {"render cornell --spp -1", "--spp"},
      {"render cornell --spp 0", "--spp"},
      {"render cornell --spp 3.5", "--spp"},
      {"render cornell --spp 1 --threads -1", "--threads"},
      {"render cornell --spp 1 --seed -1", "--seed"},
      {"render cornell --spp 1 --camera -2", "--camera"},
      {"render cornell --spp 1 --mis 'pow\ner'", "--mis"},
      {"render cornell --spp", "--spp"},
      // Resolutions: garbage, and one no machine holds (checked before the film is allocated).
      {"render cornell --spp 1 --resolution 16x16junk", "--resolution"},
      {"render cornell --spp 1 --resolution 0x16", "--resolution"},
      {"render cornell --spp 1 --resolution 16x-16", "--resolution"},
      {"render cornell --spp 1 --resolution ' 16x16'", "--resolution"},
      {"render cornell --spp 1 --resolution 99999999999x16", "--resolution"},
      {"render cornell --spp 1 --resolution 100000x100000", "memory"},
      // Control bytes and long values are quoted as short, escaped excerpts.
      {"render cornell --spp 1 --integrator 'p\tt'", "'p\\x09t'"},
      {"render cornell --spp 1 --threads "
       "1111111111111111111111111111111111111111111111111111111111111111111111",
       "111'..."},
      // The scene path.
      {"render sub --spp 1", "is a directory",
       [](const fs::path& d) { fs::create_directory(d / "sub"); }},
      {"render sub.pbrt --spp 1", "is a directory",
       [](const fs::path& d) { fs::create_directory(d / "sub.pbrt"); }},
      {"render ./ --spp 1", "is a directory"},
      // Outputs that cannot be written, found before rendering.
      {"render cornell --spp 1 --outfile missing/out", "does not exist"},
      {"render cornell --spp 1 --outfile plain.txt/out", "is not a folder",
       [](const fs::path& d) { touch(d / "plain.txt"); }},
      {"render cornell --spp 1 --outfile /proc/caustica-out", "not writable"},
      {"render cornell --spp 1 --outfile locked/out", "not writable",
       [](const fs::path& d) {
         fs::create_directory(d / "locked");
         fs::permissions(d / "locked", fs::perms::owner_read | fs::perms::owner_exec);
       },
       true},
      {"render cornell --spp 1 --outfile out", "out.png' is a directory",
       [](const fs::path& d) { fs::create_directory(d / "out.png"); }},
      {"render cornell --spp 1 --outfile out.exr", "out.json' is a directory",
       [](const fs::path& d) { fs::create_directory(d / "out.json"); }},
      {"render cornell --spp 1 --integrator bpt --techniques plain.txt", "--techniques",
       [](const fs::path& d) { touch(d / "plain.txt"); }},
      // reference shares the checks.
      {"reference cornell --time nan", "--time"},
      {"reference cornell --time 1 --max-depth -2", "--max-depth"},
      {"reference cornell --time 1 --threads -4", "--threads"},
      {"reference cornell --time 1 --resolution 16x16junk", "--resolution"},
      {"reference cornell --time 1 --resolution 100000x100000", "memory"},
      {"reference cornell --time 1 --outfile missing/ref", "does not exist"},
      {"reference sub --time 1", "is a directory",
       [](const fs::path& d) { fs::create_directory(d / "sub"); }},
      // compare shares them too, and checks its reference image before rendering anything.
      {"compare cornell --time inf", "--time"},
      {"compare cornell --time 1 --seed -1", "--seed"},
      {"compare cornell --time 1 --reference-time nan", "--reference-time"},
      {"compare cornell --time 1 --reference missing.exr", "does not exist"},
      {"compare cornell --time 1 --reference notimage.exr", "not a readable image",
       [](const fs::path& d) { touch(d / "notimage.exr", "hello"); }},
      {"compare cornell --time 1 --reference sub", "is a directory",
       [](const fs::path& d) { fs::create_directory(d / "sub"); }},
      {"compare cornell --time 1 --resolution 16x16 --reference ref8.exr",
       "8x8 but the scene renders 16x16",
       [](const fs::path& d) {
         caustica::write_exr(caustica::Image(8, 8), (d / "ref8.exr").string());
       }},
      {"compare cornell --time 1 --out plain.txt", "not a folder",
       [](const fs::path& d) { touch(d / "plain.txt"); }},
      {"compare cornell --time 1 --out /proc/caustica-compare", "not writable"},
  };
  return table;
}

class HostileCli : public testing::TestWithParam<size_t> {};

TEST_P(HostileCli, RefusedBeforeRenderingWithOneLineExit2AndNoFiles) {
  const HostileCase& c = cases()[GetParam()];
  const fs::path d = cli_test::fresh_dir("hostile_" + std::to_string(GetParam()));
  if (c.setup) c.setup(d);
  std::set<std::string> before = cli_test::entries(d);
  before.insert("stderr.txt");
  // Every case fails in milliseconds; 20 s only guards against hangs on a loaded machine.
  const cli_test::CliRun r = cli_test::run(c.args, d, 20);
  if (c.needs_non_root) fs::permissions(d / "locked", fs::perms::owner_all);
  EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
  ASSERT_FALSE(r.err.empty()) << c.args;
  EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << c.args << "\n" << r.err;
  EXPECT_EQ(r.err.back(), '\n') << c.args;
  EXPECT_LT(r.err.size(), 500u) << "an excerpt, not the whole value";
  EXPECT_EQ(cli_test::entries(d), before) << c.args << ": files written or probes left";
}

// "7_render_cornell_spp_1_radius_1": the row number and its command line, for ctest -R.
std::string case_name(const testing::TestParamInfo<size_t>& info) {
  std::string name = std::to_string(info.param) + "_";
  for (const char c : std::string(cases()[info.param].args)) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c));
    if (keep)
      name += c;
    else if (name.back() != '_')
      name += '_';
    if (name.size() >= 64) break;
  }
  while (name.back() == '_') name.pop_back();
  return name;
}

// The rows that can run here: permission bits do not stop root, so a read-only folder is only a
// case for other users (the /proc row covers an unwritable folder for root).
std::vector<size_t> applicable_cases() {
  std::vector<size_t> rows;
  for (size_t i = 0; i < cases().size(); ++i)
    if (!(cases()[i].needs_non_root && ::geteuid() == 0)) rows.push_back(i);
  return rows;
}

INSTANTIATE_TEST_SUITE_P(Table, HostileCli, testing::ValuesIn(applicable_cases()), case_name);

}  // namespace
