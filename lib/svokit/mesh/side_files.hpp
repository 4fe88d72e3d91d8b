#pragma once
// Which side files an import may read (textures, material libraries, glTF buffers): one rule for
// every format, so that a service baking uploaded models can rely on it. A side file is read only
// if, resolved canonically (symlinks and ".." followed), it lies inside the model's folder or its
// subfolders, or inside a folder the user allowed (--asset-path). Absolute paths, "../", percent
// escapes and file:// URIs all go through the same check; data: URIs are not side files.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "svokit/core/status.hpp"
#include "svokit/mesh/orientation.hpp"

namespace svokit {

/// What an import may read besides the mesh file itself, and how it turns the file's axes.
struct ImportOptions {
  /// Folders (and their subfolders) side files may lie in besides the model's own (--asset-path).
  std::vector<std::filesystem::path> asset_paths;
  /// The rotation from the source file's axes to svokit's (--up, --rotate); unset: the one the
  /// file records (a .svm's), else none. ImportMesh applies it (mesh_import.hpp).
  std::optional<Orientation> orientation;
};

/// How a format writes a reference to a side file.
enum class SideFileSyntax {
  kUri,   ///< glTF: a URI reference, percent-encoded; file:// URIs name local files
  kPath,  ///< OBJ and MTL: a file path as written, backslashes taken as separators
};

/// The folders one model's side files may come from.
class SideFileRule {
 public:
  /// `model`: the mesh file as given (its folder, canonical, is the first allowed one).
  SideFileRule(const std::filesystem::path& model, const ImportOptions& options);

  /// The file `reference` names (written in `syntax`, relative to `folder`, the folder of the
  /// file that names it), absolute and canonical, when the rule allows reading it. Otherwise
  /// kBadInput with the reason, worded to follow the quoted reference: "resolves to /etc/passwd,
  /// outside the model's folder (--asset-path DIR allows it)". Whether the file exists is not
  /// checked (a refused file's existence is not revealed).
  StatusOr<std::filesystem::path> Resolve(std::string_view reference, SideFileSyntax syntax,
                                          const std::filesystem::path& folder) const;

  /// The model's folder, as given (relative references in the model resolve against it).
  const std::filesystem::path& model_folder() const { return model_folder_; }

 private:
  std::filesystem::path model_folder_;
  std::vector<std::filesystem::path> roots_;  ///< canonical
};

/// Refuses `output` when it is one of `inputs` (the same file, by device and inode, as
/// CheckOutputPath compares): kBadInput "OUT: is the input file IN; write the output elsewhere".
/// Inputs include the side files an import read (Mesh::side_files), so that no output replaces a
/// texture, material library or buffer of its own mesh.
Status CheckNotAnInput(const std::filesystem::path& output,
                       const std::vector<std::filesystem::path>& inputs);

/// `uri` with its percent escapes decoded ("my%20tex.png" → "my tex.png"); a malformed escape is
/// kept as written.
std::string PercentDecode(std::string_view uri);

}  // namespace svokit
