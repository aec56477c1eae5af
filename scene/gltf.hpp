#pragma once
// glTF 2.0 (.gltf / .glb) import and export through tinygltf.

#include <filesystem>
#include <string>
#include <vector>

#include "scene/types.hpp"

namespace radar_emu::scene {

/// Loads a glTF 2.0 file (.glb binary or .gltf JSON with data: URIs or external .bin buffers;
/// the binary container is recognised by its magic). One ObjectDesc per node with a mesh, named
/// after the node ("node<i>" when unnamed), in scene-graph order. Every mesh primitive must be
/// TRIANGLES with float VEC3 POSITION, u8/u16/u32 indices (or none) and a named material; the
/// material's name is the radar material name (equal names are one material). glTF's y-up frame
/// is converted to ENU (x east, y north, z up) as x_enu = x, y_enu = -z, z_enu = y. A static
/// node's accumulated transform becomes ObjectDesc::world_from_body (in double; vertices stay in
/// the node's frame, ENU axes; mirroring transforms get their winding reversed). A node whose
/// extras hold {"radar_emu": {"velocity_mps": [e, n, u]}} becomes a moving object: its rotation
/// and scale are baked into the body vertices, "start_position_m": [e, n, u] (default: the
/// node's translation) is the start. A node whose extras hold {"radar_emu": {"trajectory":
/// {"waypoints_m": [[e, n, u], ...], "speed_mps": v, "turn_radius_m": r, "turn_rate_rad_s": w,
/// "loop": bool, "bank": bool}}} moves on that scene::Trajectory (waypoints and speed required;
/// rotation and scale baked in as above, translation ignored; velocity_mps and trajectory are
/// exclusive). Node extras radar_emu "area" (string), "lod_group" (integer >= -1), "lod_level"
/// (0..255) and "lod_facet_m" (number >= 0) fill the ObjectDesc fields of the same names.
/// Material extras {"radar_emu": {"radar_material": NAME}} name the radar material (else the
/// glTF material's name). The anchor is read from the scene's extras
/// {"radar_emu": {"anchor_deg_m": [lat, lon, h]}} when present (else 0, 0, 0).
/// Throws std::runtime_error "FILE: reason" for anything broken or unsupported (sparse or
/// out-of-bounds accessors, bad indices, other modes, missing materials, node cycles, required
/// extensions, only degenerate triangles); never reads out of bounds. Degenerate triangles are
/// dropped and, like open or non-manifold surfaces, reported in `warnings` when it is given
/// (scene/mesh_check.hpp). Setup only.
[[nodiscard]] SceneDescription load_gltf(const std::filesystem::path& path,
                                         std::vector<std::string>* warnings = nullptr);

/// Writes `description` as glTF 2.0 (binary .glb when the extension is .glb, otherwise JSON with
/// the buffer embedded as a data: URI), materials by name (and in extras radar_material), static
/// placements as node matrices, moving objects, trajectories, area, LOD fields and anchor in
/// extras as load_gltf() reads them; load_gltf(write_gltf(d)) gives back d (same objects,
/// vertices, triangle order, materials, motions and extras). Throws std::runtime_error
/// "FILE: reason" on I/O failure or an inconsistent description.
void write_gltf(const SceneDescription& description, const std::filesystem::path& path);

}  // namespace radar_emu::scene
