#pragma once
// glTF 2.0 (.gltf / .glb) import and export through tinygltf.

#include <filesystem>

#include "scene/types.hpp"

namespace radar_emu::scene {

/// Loads a glTF 2.0 file. Every mesh primitive must be TRIANGLES with a material; the material's
/// name is the radar material name. Node transforms are applied; glTF's y-up frame is converted
/// to ENU (x east, y north, z up) as x_enu = x, y_enu = -z, z_enu = y. A node whose extras hold
/// {"radar_emu": {"velocity_mps": [e, n, u]}} becomes a moving object. The anchor is read from
/// the scene's extras {"radar_emu": {"anchor_deg_m": [lat, lon, h]}} when present.
/// Throws std::runtime_error "FILE: reason" for anything broken.
[[nodiscard]] SceneDescription load_gltf(const std::filesystem::path& path);

/// Writes `description` as glTF 2.0 (binary .glb when the extension is .glb), materials by name,
/// moving objects and anchor in extras as load_gltf() reads them. Throws on I/O failure.
void write_gltf(const SceneDescription& description, const std::filesystem::path& path);

}  // namespace radar_emu::scene
