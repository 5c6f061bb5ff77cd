#include "dynamics/marker_track.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "core/errors.hpp"
#include "io/input_file.hpp"

namespace msfab {
namespace {

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

std::vector<std::string> split_cells(const std::string& line) {
  std::vector<std::string> cells;
  std::string::size_type start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma - start)));
    if (comma == std::string::npos) return cells;
    start = comma + 1;
  }
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", x);
  return buf;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "'" : ", '") + n + "'";
  return out;
}

}  // namespace

MarkerTrack read_marker_track(const std::string& path, const std::string& column, const MarkerTrackOptions& options) {
  if (options.min_samples < 2 || !(options.uniform_tolerance > 0.0))
    throw InputError(path + ": marker track options: min_samples = " + std::to_string(options.min_samples) +
                     " must be >= 2 and uniform_tolerance = " + num(options.uniform_tolerance) + " positive");
  std::istringstream in(read_text_file(path, kMaxTextInputBytes));
  auto error = [&](int line, const std::string& what) {
    return InputError(path + (line > 0 ? ": line " + std::to_string(line) : std::string()) + ": " + what);
  };

  std::vector<std::string> header;
  int time_col = -1, value_col = -1;
  std::vector<double> t, v;
  std::vector<int> lines;  // file line of each sample, for messages
  std::string text;
  for (int line_no = 1; std::getline(in, text); ++line_no) {
    const std::string line = trim(text);
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells = split_cells(line);
    if (header.empty()) {
      header = cells;
      for (int c = 0; c < static_cast<int>(header.size()); ++c) {
        if (header[c].empty()) throw error(line_no, "header column " + std::to_string(c + 1) + " has no name");
        if (std::count(header.begin(), header.end(), header[c]) > 1)
          throw error(line_no, "duplicate column '" + header[c] + "'");
        const std::string l = lower(header[c]);
        if ((l == "t" || l == "time") && time_col < 0) time_col = c;
      }
      if (time_col < 0) throw error(line_no, "no time column ('t' or 'time') among " + join(header));
      std::vector<std::string> coords;
      for (int c = 0; c < static_cast<int>(header.size()); ++c)
        if (c != time_col) coords.push_back(header[c]);
      if (column.empty()) {
        if (coords.size() != 1)
          throw error(line_no, "choose a coordinate column: the file has " + std::to_string(coords.size()) + " (" +
                                   join(coords) + ")");
        value_col = time_col == 0 ? 1 : 0;
      } else {
        const auto it = std::find(header.begin(), header.end(), column);
        if (it == header.end() || it - header.begin() == time_col)
          throw error(line_no, "no coordinate column '" + column + "' (columns: " + join(coords) + ")");
        value_col = static_cast<int>(it - header.begin());
      }
      continue;
    }
    if (cells.size() != header.size())
      throw error(line_no, std::to_string(cells.size()) + " cells, header has " + std::to_string(header.size()));
    double parsed[2];
    const int want[2] = {time_col, value_col};
    for (int i = 0; i < 2; ++i) {
      const std::string& cell = cells[want[i]];
      const std::string where = "column '" + header[want[i]] + "'";
      char* end = nullptr;
      errno = 0;
      parsed[i] = std::strtod(cell.c_str(), &end);
      if (cell.empty() || *end != '\0') throw error(line_no, where + ": '" + cell + "' is not a number");
      if (!std::isfinite(parsed[i]) || errno == ERANGE)
        throw error(line_no, where + ": '" + cell + "' is not a finite number");
    }
    if (!t.empty() && !(parsed[0] > t.back()))
      throw error(line_no,
                  "time " + cells[time_col] + " does not increase (previous row " + std::to_string(lines.back()) + ")");
    t.push_back(parsed[0]);
    v.push_back(parsed[1]);
    lines.push_back(line_no);
  }
  if (in.bad()) throw error(0, "read error");
  if (header.empty()) throw error(0, "no header line (e.g. 't,x')");
  const int n = static_cast<int>(t.size());
  if (n < options.min_samples)
    throw error(0, std::to_string(n) + " samples in column '" + header[value_col] + "': need at least " +
                       std::to_string(options.min_samples));

  MarkerTrack track;
  track.source = path;
  track.column = header[value_col];
  track.times = Eigen::Map<const VecX>(t.data(), n);
  track.values = Eigen::Map<const VecX>(v.data(), n);
  track.sample_interval = (t.back() - t.front()) / (n - 1);
  // Steps are compared with the median step, which a single dropped or
  // repeated frame does not move, so the message points at that frame.
  std::vector<double> steps(n - 1);
  for (int k = 1; k < n; ++k) steps[k - 1] = t[k] - t[k - 1];
  std::vector<double> sorted = steps;
  std::nth_element(sorted.begin(), sorted.begin() + (n - 1) / 2, sorted.end());
  const double h = sorted[(n - 1) / 2];
  for (int k = 1; k < n; ++k) {
    const double step = steps[k - 1];
    if (std::abs(step - h) > options.uniform_tolerance * h)
      throw error(lines[k], "time step " + num(step) + " differs from the median step " + num(h) + " by more than " +
                                num(options.uniform_tolerance) +
                                " relative: sampling must be uniform (dropped or repeated frame?)");
  }
  return track;
}

}  // namespace msfab
