// Command-line values that used to bake nonsense with exit 0 (issue #14,
// items 5 and 6) now fail up front, naming the option.
#include <gtest/gtest.h>

#include <sstream>

#include "pipeline/cell_grid.h"
#include "pipeline/ingest.h"
#include "tests/fixture_room_obj.h"
#include "tests/test_support.h"

namespace cellbake {
namespace {

class CliValues : public ::testing::Test {
 protected:
  void SetUp() override {
    std::ostringstream o;
    int next = 1;
    test::obj_box(o, next, {0, 0, 0}, {4, 4, 3}, 2);
    test::write_text(dir_ / "box.obj", o.str());
    ingest_models({dir_ / "box.obj"}, dir_ / "s.db", IngestParams{},
                  [](std::size_t n, const std::function<void(std::size_t)>& fn) {
                    for (std::size_t i = 0; i < n; ++i) fn(i);
                  });
  }
  test::CommandResult bake(const std::string& extra) {
    return test::run_cellbake("bake --store " + (dir_ / "s.db").string() + " --face-size 16 --quiet --out " +
                              (dir_ / "cells.db").string() + " " + extra);
  }
  void expect_refused(const std::string& extra, const std::string& message) {
    const auto r = bake(extra);
    EXPECT_NE(r.exit_code, 0) << extra << ": " << r.output;
    EXPECT_NE(r.output.find(message), std::string::npos) << extra << ": " << r.output;
  }
  test::TempDir dir_;
};

TEST_F(CliValues, NonFiniteCellSizesAndRegionsAreRefused) {
  expect_refused("--region=1,1,1,3,3,2 --cell-size nan", "--cell-size must be a finite number");
  expect_refused("--region=1,1,1,3,3,2 --cell-size inf", "--cell-size");
  expect_refused("--region=1,1,1,inf,3,2 --cell-size 2", "not a finite number");
  expect_refused("--region=1,nan,1,3,3,2 --cell-size 2", "not a finite number");
  EXPECT_FALSE(std::filesystem::exists(dir_ / "cells.db"));
}

TEST_F(CliValues, HugeRegionsAreAnErrorNotOverflow) {
  expect_refused("--region=0,0,0,1e18,1,1 --cell-size 1", "cells of size");
  expect_refused("--region=0,0,0,1e6,1e6,1e6 --cell-size 1", "more than");
  EXPECT_THROW(enumerate_cells({Box3d{{0, 0, 0}, {1e300, 1, 1}}}, 1e-300), std::invalid_argument);
}

TEST_F(CliValues, EmptyCellSelectionsFailNamingTheRange) {
  expect_refused("--region=1,1,1,3,3,2 --cell-size 2 --cells 100-200", "selects none of the 1 cells (ids 1 to 1)");
  ASSERT_EQ(bake("--region=1,1,1,3,3,2 --cell-size 2").exit_code, 0);
  const auto v = test::run_cellbake("verify --walk-seconds 0 " + (dir_ / "cells.db").string() + " --cells 500-600 --report " +
                                    (dir_ / "report").string());
  EXPECT_NE(v.exit_code, 0) << v.output;
  EXPECT_NE(v.output.find("selects none"), std::string::npos) << v.output;
}

}  // namespace
}  // namespace cellbake
