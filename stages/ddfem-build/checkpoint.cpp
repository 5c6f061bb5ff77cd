#include "checkpoint.hpp"

#include <cstdio>
#include <vector>

#include "core/errors.hpp"
#include "fit_record.hpp"
#include "io/atomic_file.hpp"
#include "io/hdf5_file.hpp"

namespace msfab {

std::string checkpoint_path(const std::string& out) { return out + ".checkpoint.h5"; }

void write_checkpoint(const std::string& path, const std::string& config_text, const FittedOrbits& done, int points) {
  const int size = fit_record_size(points);
  AtomicFile tmp(path);
  {
    H5File f = H5File::create_in(tmp);
    f.write_attribute("/", "schema", "msfab.coarse_db.checkpoint");
    f.write_attribute("/", "config", config_text);
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
    f.close();
  }
  tmp.commit();
}

FittedOrbits read_checkpoint(const std::string& path, const std::string& config_text, int points) {
  const H5File f = H5File::open(path);
  if (!f.exists("/orbits") || f.read_string_attribute("/", "schema") != "msfab.coarse_db.checkpoint")
    throw InputError(path + ": not a database-builder checkpoint");
  if (f.read_string_attribute("/", "config") != config_text)
    throw InputError(path + ": checkpoint was written with a different configuration; delete it or rerun without --resume");
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
