// Field tables (io/field_table.hpp): a struct's fields and a history's
// columns read back exactly under the names written, of the types written;
// columns of unequal length are an input error naming the dataset.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "core/errors.hpp"
#include "io/field_table.hpp"

namespace msfab {
namespace {
namespace fs = std::filesystem;

struct RunSummary {
  std::string name;
  double error = 0;
  std::int32_t steps = 0;
  std::int64_t substeps = 0;
};
struct HistoryRow {
  std::int32_t cycle = 0;
  double coverage = 0;
};

const FieldOf<RunSummary> kSummaryFields[] = {MSFAB_FIELD(RunSummary, name),
                                              MSFAB_FIELD(RunSummary, error),
                                              MSFAB_FIELD(RunSummary, steps),
                                              {"substeps_taken", &RunSummary::substeps}};
const FieldOf<HistoryRow> kRowFields[] = {MSFAB_FIELD(HistoryRow, cycle), MSFAB_FIELD(HistoryRow, coverage)};

fs::path field_table_scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("msfab_field_table_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

TEST(FieldTable, AttributesReadBackUnderTheirNamesAndTypes) {
  const std::string path = field_table_scratch("attributes.h5").string();
  const RunSummary written{"drop", 0.125, 7, std::int64_t(1) << 40};
  {
    H5File f = H5File::create(path);
    write_attribute_fields(f, "/", written, kSummaryFields);
  }
  const H5File f = H5File::open(path);
  EXPECT_EQ(f.read_string_attribute("/", "name"), "drop");
  EXPECT_EQ(f.read_attribute<std::int64_t>("/", "substeps_taken"), std::int64_t(1) << 40);
  RunSummary read;
  read_attribute_fields(f, "/", read, kSummaryFields);
  EXPECT_EQ(read.name, written.name);
  EXPECT_EQ(read.error, written.error);
  EXPECT_EQ(read.steps, written.steps);
  EXPECT_EQ(read.substeps, written.substeps);
}

TEST(FieldTable, ColumnsRoundTripAndAnEmptyHistoryWritesNothing) {
  const std::string path = field_table_scratch("columns.h5").string();
  const std::vector<HistoryRow> rows = {{0, 0.25}, {1, 0.5}, {2, 0.625}};
  {
    H5File f = H5File::create(path);
    write_column_fields(f, "/history", rows, kRowFields);
    write_column_fields(f, "/empty", std::vector<HistoryRow>{}, kRowFields);
  }
  const H5File f = H5File::open(path);
  EXPECT_EQ(f.read_vector<std::int32_t>("/history/cycle"), (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_FALSE(f.exists("/empty"));
  const std::vector<HistoryRow> read = read_column_fields(f, "/history", kRowFields);
  ASSERT_EQ(read.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(read[i].cycle, rows[i].cycle);
    EXPECT_EQ(read[i].coverage, rows[i].coverage);
  }
  EXPECT_TRUE(read_column_fields(f, "/empty", kRowFields).empty());
}

TEST(FieldTable, ColumnsOfUnequalLengthAreAnInputError) {
  const std::string path = field_table_scratch("unequal.h5").string();
  {
    H5File f = H5File::create(path);
    f.write_vector("/history/cycle", std::vector<std::int32_t>{0, 1, 2});
    f.write_vector("/history/coverage", std::vector<double>{0.25, 0.5});
  }
  const H5File f = H5File::open(path);
  try {
    read_column_fields(f, "/history", kRowFields);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/history/coverage"), std::string::npos) << what;
    EXPECT_NE(what.find("unequal.h5"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace msfab
