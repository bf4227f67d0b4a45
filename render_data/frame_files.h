#pragma once
// Encoding and decoding of one frame's files in the cgsr dataset format (dataset_manifest.h).
// Writers are atomic; readers validate what they decode and throw cgsr::Error whose context is
// the file and whose message names the frame: wrong size, NaN/Inf, negative depth, zero-length
// normals on geometry, edge values other than 0/1, corrupt or missing files.

#include <filesystem>
#include <vector>

#include "render_data/dataset_manifest.h"
#include "render_data/frame.h"
#include "render_data/gbuffer.h"

namespace cgsr {

// Writes every file kind of `g` for (resolution, frame); returns the bytes written per kind
// (in all_file_kinds() order). Files are encoded in parallel.
std::vector<size_t> write_frame_files(const std::filesystem::path& root, const Resolution& resolution, int frame,
                                      const GBuffer& g);

// True when every file of `frame` exists at every resolution (writes are atomic, so an existing
// file is a complete one).
bool frame_complete(const std::filesystem::path& root, const std::vector<Resolution>& resolutions, int frame);

// What can be wrong with one file (data check counts these; the readers throw them).
enum class FileProblem { None, Missing, Unreadable, WrongSize, NonFinite, OutOfRange, ZeroNormal };
const char* file_problem_name(FileProblem problem);  // "missing", "unreadable", "wrong size", ...

struct DecodedFile {
  torch::Tensor value;  // as the matching read_*_file returns it; undefined on a problem
  FileProblem problem = FileProblem::None;
  std::string message;  // "frame N: ..." when there is a problem
};
// Decodes and validates one file of the dataset format without throwing. `depth` (linear) is
// used for normals only (unit length where there is geometry, 0 elsewhere).
DecodedFile decode_file(FileKind kind, const std::filesystem::path& path, int frame, const Resolution& expected,
                        const torch::Tensor& depth = {});

// Per-file decoders. `frame` is only used in error messages.
torch::Tensor read_color_file(const std::filesystem::path& path, int frame, const Resolution& expected);   // uint8 [3,H,W]
torch::Tensor read_depth_file(const std::filesystem::path& path, int frame, const Resolution& expected);   // float [1,H,W]
// `depth` (linear, +inf = no geometry) marks where normals must be unit length and where they are 0.
torch::Tensor read_normal_file(const std::filesystem::path& path, int frame, const Resolution& expected,
                               const torch::Tensor& depth);                                                 // half [3,H,W]
torch::Tensor read_normal_angle_file(const std::filesystem::path& path, int frame, const Resolution& expected);  // half
torch::Tensor read_edge_file(const std::filesystem::path& path, int frame, const Resolution& expected);    // uint8 [1,H,W]
torch::Tensor read_id_file(const std::filesystem::path& path, int frame, const Resolution& expected);      // int32 [2,H,W]
torch::Tensor read_motion_file(const std::filesystem::path& path, int frame, const Resolution& expected);  // float [2,H,W]

// Reads the requested channels (plus colour) of one frame at one resolution.
Frame read_dataset_frame(const std::filesystem::path& root, const DatasetManifest& manifest, int frame,
                         size_t resolution, const std::vector<RenderChannel>& channels);

// Validation shared by every loader: throws naming `context` and the frame.
void check_image_size(const torch::Tensor& image, const Resolution& expected, const std::string& context, int frame);
void check_finite(const torch::Tensor& values, const std::string& context, int frame, const char* what);
void check_unit_normals(const torch::Tensor& normal, const torch::Tensor& depth, const std::string& context, int frame);

}  // namespace cgsr
