#include "family_pictures.hpp"

#include <algorithm>
#include <filesystem>

#include "families/beam_template.hpp"
#include "io/path_names.hpp"
#include "io/png_image.hpp"

namespace msfab {

namespace {

bool solid(const std::vector<int>& ids, int n, int i, int j, int k) {
  return ids[std::size_t(i) + std::size_t(n) * (std::size_t(j) + std::size_t(n) * k)] != 0;
}

// Voxel (i, j) of an n x n view as a scale x scale block, y up.
void paint_voxel(PngImage& image, int x0, int y0, int scale, int n, int i, int j, std::uint8_t grey) {
  for (int a = 0; a < scale; ++a)
    for (int b = 0; b < scale; ++b) image.set(x0 + i * scale + a, y0 + (n - 1 - j) * scale + b, {grey, grey, grey});
}

// A structure seen along z: each pixel's grey is the depth of the first
// solid voxel (near = dark), so beams in front read as darker than those
// behind; void through the whole cell is white.
void draw_depth_view(PngImage& image, int x0, int y0, int scale, const std::vector<int>& ids, int n) {
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int depth = 0;
      while (depth < n && !solid(ids, n, i, j, depth)) ++depth;
      paint_voxel(image, x0, y0, scale, n, i, j, depth == n ? 255 : std::uint8_t(30 + 170 * depth / n));
    }
}

// One layer of a structure: solid black, void white.
void draw_slice(PngImage& image, int x0, int y0, int scale, const std::vector<int>& ids, int n, int k) {
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) paint_voxel(image, x0, y0, scale, n, i, j, solid(ids, n, i, j, k) ? 30 : 255);
}

}  // namespace

std::string picture_folder_for(const std::string& out) {
  return without_suffix(out, {".families.h5", ".h5"}) + ".plots";
}

void write_family_pictures(const std::string& folder, const FamiliesResult& r, const MicrostructureSet& set) {
  std::filesystem::create_directories(folder);
  // Per family: representative (left) and its fitted template (right), at
  // the set's resolution, one pixel block per voxel: seen along z with
  // depth shading (top), and the layers z = n/4 and z = 0 (below), which
  // cut through the fundamental tetrahedron and the cell face.
  const int n = set.nx, scale = std::max(1, 192 / n), gap = 12, side = n * scale;
  for (std::size_t f = 0; f < r.families.size(); ++f) {
    const FamilyRecord& fam = r.families[f];
    PngImage image(2 * side + 3 * gap, 3 * side + 4 * gap, {255, 255, 255});
    const std::vector<int>& rep = set.items[std::size_t(fam.representative)].ids;
    std::vector<int> tpl;
    if (fam.representative_template.size() > 0)
      tpl = rasterize_template(template_from_parameters(fam.representative_template, fam.caps), n).ids;
    for (int col = 0; col < 2; ++col) {
      const std::vector<int>& ids = col == 0 ? rep : tpl;
      if (ids.empty()) continue;
      const int x0 = gap + col * (side + gap);
      draw_depth_view(image, x0, gap, scale, ids, n);
      draw_slice(image, x0, 2 * gap + side, scale, ids, n, n / 4);
      draw_slice(image, x0, 3 * gap + 2 * side, scale, ids, n, 0);
    }
    image.write_png(folder + "/family" + std::to_string(f + 1) + ".png");
  }
}

}  // namespace msfab
