// Output files appear whole or not at all.
#include <gtest/gtest.h>

#include <fstream>
#include <stdexcept>

#include "cncstream/jobs/output_file.hpp"
#include "jobs_test_util.hpp"

using namespace cncstream;
using namespace jobstest;

namespace {

std::string read_all(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

}  // namespace

TEST(OutputFile, AWriterFailingHalfWayLeavesTheOldFileAndNoTemporary) {
  const fs::path dir = temp_dir("output");
  const fs::path target = dir / "part.nc";
  jobs::write_text_file_atomically(target, "G0 X0\n");
  EXPECT_THROW(jobs::write_file_atomically(target,
                                           [](const fs::path& file) {
                                             std::ofstream f(file);
                                             f << "G0 X1\nG1 Y";  // half a program
                                             f.close();
                                             throw std::runtime_error("disk full");
                                           }),
               std::runtime_error);
  EXPECT_EQ(read_all(target), "G0 X0\n");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"part.nc"});
}

TEST(OutputFile, TwoWritersOfOneTargetUseTemporariesOfTheirOwn) {
  const fs::path dir = temp_dir("output2");
  const fs::path target = dir / "part.nc";
  fs::path first_tmp, second_tmp;
  // The second write starts while the first is still writing its temporary.
  jobs::write_file_atomically(target, [&](const fs::path& file) {
    first_tmp = file;
    std::ofstream(file) << "first\n";
    jobs::write_file_atomically(target, [&](const fs::path& inner) {
      second_tmp = inner;
      std::ofstream(inner) << "second\n";
    });
  });
  EXPECT_NE(first_tmp, second_tmp);
  EXPECT_NE(first_tmp, fs::path(target.string() + ".part"));  // a user's own X.part is not touched
  EXPECT_EQ(read_all(target), "first\n");  // the last to finish wins, whole
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"part.nc"});
}
