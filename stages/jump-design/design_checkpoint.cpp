#include "design_checkpoint.hpp"

#include <filesystem>
#include <mutex>

#include "core/errors.hpp"
#include "io/checkpoint_file.hpp"

namespace msfab {

namespace {
constexpr const char* kSchema = "msfab.jump_design.checkpoint";
// HDF5 (Debian's build) is not thread-safe; starts on the threads of one
// rank take turns writing. A mutex, not an OpenMP critical section: a failed write
// throws, and must release it.
std::mutex hdf5_mutex;
}  // namespace

std::string start_checkpoint_path(const std::string& out, int start) {
  return out + ".start" + std::to_string(start) + ".checkpoint.h5";
}

std::string sample_checkpoint_path(const std::string& out, int sample) {
  return out + ".sample" + std::to_string(sample) + ".checkpoint.h5";
}

void write_evaluations_checkpoint(const std::string& path, const std::string& run_text, const DesignProblem& problem,
                                  const std::vector<Evaluation>& evaluations) {
  const std::size_t per = static_cast<std::size_t>(evaluation_record_size(problem));
  std::vector<double> rows(evaluations.size() * per);
  for (std::size_t i = 0; i < evaluations.size(); ++i) pack_evaluation(problem, evaluations[i], rows.data() + i * per);
  const std::lock_guard<std::mutex> lock(hdf5_mutex);
  write_checkpoint_file(path, kSchema, run_text, [&](H5File& f) {
    f.write_dataset("/evaluations", rows, {hsize_t(evaluations.size()), hsize_t(per)});
  });
}

std::vector<Evaluation> read_evaluations_checkpoint(const std::string& path, const std::string& run_text,
                                                    const DesignProblem& problem) {
  std::vector<Evaluation> evaluations;
  if (!std::filesystem::exists(path)) return evaluations;
  const H5File f = open_checkpoint_file(path, kSchema, "jump-design", run_text);
  const NdArray<double> rows = f.read_dataset<double>("/evaluations", Finite::nan_means_missing);
  const std::size_t per = static_cast<std::size_t>(evaluation_record_size(problem));
  if (rows.shape.size() != 2 || rows.shape[1] != per)
    throw InputError(path + ": /evaluations has rows of another length than this design problem's");
  for (std::size_t i = 0; i < rows.shape[0]; ++i)
    evaluations.push_back(unpack_evaluation(problem, &rows.values[i * per]));
  return evaluations;
}

}  // namespace msfab
