// Path containment for the files a model names (OBJ mtllib, MTL map_Kd, glTF
// buffer and image URIs, anything assimp opens beside the model): by default
// they are read only from the model's folder and its subfolders, so a model
// file cannot make ingest read an arbitrary file ("../../../../etc/passwd").
// `cellbake ingest --allow-outside-paths` lifts the rule (ReadOptions).
#pragma once

#include <filesystem>
#include <string>

namespace cellbake {

// True when `reference` (a path a model names, already joined to the folder it
// is relative to) lies inside `folder` or one of its subfolders. Both are made
// absolute and resolved with std::filesystem::weakly_canonical first, so ".."
// steps and symbolic links (of the existing part of the path) are followed
// before comparing: a link inside the folder to a file outside it is outside.
// An empty `folder` is the current directory.
bool path_inside_folder(const std::filesystem::path& folder, const std::filesystem::path& reference);

// The file a texture reference in a model names, as exporters write them:
// relative to `folder` (the folder of the file holding the reference) or
// absolute, with '\\' or '/' separators. When that file does not exist (a
// path on the exporter's machine, "D:\\maps\\wood.jpg", or a name whose case
// differs from the file's), the file of that name in `folder` itself, matched
// exactly, else ignoring ASCII case (the first in name order). Returns the
// reference as written, joined to `folder`, when neither exists (the caller
// reports it missing). Never looks outside `folder`.
std::filesystem::path locate_referenced_file(const std::filesystem::path& folder, std::string reference);

// The words every refusal uses, e.g. "mtllib '../a.mtl': " + kOutsideFolder.
inline const std::string kOutsideFolder =
    "outside the model's folder, not read (--allow-outside-paths allows it)";

}  // namespace cellbake
