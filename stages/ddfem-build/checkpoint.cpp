#include "checkpoint.hpp"

#include <cstdio>
#include <vector>

#include "core/errors.hpp"
#include "fit_record.hpp"
#include "io/checkpoint_file.hpp"

namespace msfab {

void write_checkpoint(const std::string& path, const std::string& config_text, const FittedOrbits& done, int points) {
  const int size = fit_record_size(points);
  write_checkpoint_file(path, "msfab.coarse_db.checkpoint", config_text, [&](H5File& f) {
    MatX rows(done.size(), 1 + size);
    int r = 0;
    for (const auto& [code, fit] : done) {
      std::vector<double> record(size);
      pack_fit(fit, record.data());
      rows(r, 0) = static_cast<double>(code);
      for (int j = 0; j < size; ++j) rows(r, 1 + j) = record[j];
      ++r;
    }
    f.write_matrix("/orbits", rows);
  });
}

FittedOrbits read_checkpoint(const std::string& path, const std::string& config_text, int points) {
  const H5File f = open_checkpoint_file(path, "msfab.coarse_db.checkpoint", "database-builder", config_text);
  if (!f.exists("/orbits")) throw InputError(path + ": the checkpoint has no /orbits");
  const MatX rows = f.read_matrix<double>("/orbits");
  if (rows.cols() != 1 + fit_record_size(points))
    throw InputError(path + ": /orbits has " + std::to_string(rows.cols()) + " columns, expected " +
                     std::to_string(1 + fit_record_size(points)) + " (fits of " + std::to_string(points) + " points)");
  FittedOrbits done;
  for (int r = 0; r < rows.rows(); ++r) {
    const Eigen::Matrix<double, 1, Eigen::Dynamic> row = rows.row(r);
    done[static_cast<std::int64_t>(row[0])] = unpack_fit(row.data() + 1, points);
  }
  return done;
}

}  // namespace msfab
