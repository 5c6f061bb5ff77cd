#pragma once
// Tracked marker trajectory of a calibration rig (thesis §4.3.2): one
// coordinate of a marker, sampled uniformly in time (high-speed video),
// read from CSV for harmonic inversion.
//
// Format: optional '#' comment lines, a header naming the columns, then one
// row per frame; cells separated by ',', surrounding blanks ignored, blank
// lines skipped. The time column is named "t" or "time" (any case), e.g.
//   t,x,y            time,z
//   0.0,1.2,3.4      0.0,0.01
// Cells of the time and the selected column must be finite numbers (other
// columns are not read: another marker may have lost tracking). Times must increase, with every step
// within `uniform_tolerance` (relative) of the median step: the harmonic
// inversion assumes uniform sampling, and video frames that were dropped or
// duplicated would silently bias the frequency, so they are reported, not
// resampled.
#include <string>

#include "core/types.hpp"

namespace msfab {

struct MarkerTrackOptions {
  int min_samples = 16;
  double uniform_tolerance = 1e-3;
};

struct MarkerTrack {
  std::string source;            // the file read
  std::string column;            // the coordinate column selected
  VecX times;                    // s, as in the file
  VecX values;                   // the selected coordinate
  double sample_interval = 0.0;  // mean time step
};

// Reads `path` and selects the coordinate `column`; an empty `column`
// selects the only non-time column. InputError, naming the file (and line
// and column where there is one) for: a missing or unreadable file, a
// missing, duplicate or unknown column, a row with the wrong number of
// cells, a non-numeric or non-finite cell, non-increasing or non-uniform
// times, or fewer than min_samples rows.
MarkerTrack read_marker_track(const std::string& path, const std::string& column = "",
                              const MarkerTrackOptions& options = {});

}  // namespace msfab
