#include "scene/geodata/osm.hpp"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <regex>
#include <set>
#include <stdexcept>
#include <string>

#include "common/units.hpp"

namespace radar_emu::scene::geodata {
namespace {

// "k"=>"v","k2"=>"v2" (GDAL's hstore form of other_tags; quotes inside values are escaped).
void parse_other_tags(const std::string& s, Tags& tags) {
  std::size_t i = 0;
  auto quoted = [&](std::string& out) {
    out.clear();
    if (i >= s.size() || s[i] != '"')
      return false;
    for (++i; i < s.size() && s[i] != '"'; ++i) {
      if (s[i] == '\\' && i + 1 < s.size())
        ++i;
      out += s[i];
    }
    ++i;  // closing quote
    return true;
  };
  std::string k, v;
  while (i < s.size()) {
    if (!quoted(k))
      return;
    if (s.compare(i, 2, "=>") != 0)
      return;
    i += 2;
    if (!quoted(v))
      return;
    tags[k] = v;
    if (i < s.size() && s[i] == ',')
      ++i;
  }
}

Tags feature_tags(OGRFeature& f) {
  Tags tags;
  for (int k = 0; k < f.GetFieldCount(); ++k) {
    if (!f.IsFieldSetAndNotNull(k))
      continue;
    const std::string name = f.GetFieldDefnRef(k)->GetNameRef();
    if (name == "osm_id" || name == "osm_way_id" || name == "z_order")
      continue;
    if (name == "other_tags")
      parse_other_tags(f.GetFieldAsString(k), tags);
    else
      tags[name] = f.GetFieldAsString(k);
  }
  return tags;
}

std::vector<LonLat> ring_points(const OGRSimpleCurve& c) {
  std::vector<LonLat> out;
  out.reserve(static_cast<std::size_t>(c.getNumPoints()));
  for (int i = 0; i < c.getNumPoints(); ++i)
    out.push_back({common::radians(c.getX(i)), common::radians(c.getY(i))});
  return out;
}

// GDAL reports ways with missing nodes only as debug messages: collected here.
struct BrokenWays {
  std::set<std::int64_t> ids;
};
void CPL_STDCALL collect(CPLErr cls, CPLErrorNum, const char* msg) {
  auto* self = static_cast<BrokenWays*>(CPLGetErrorHandlerUserData());
  if (cls != CE_Debug || self == nullptr || msg == nullptr)
    return;
  static const std::regex kMissing(R"(For way (-?\d+), got only)");
  static const std::regex kDiscard(R"(Way (-?\d+) with \d+ nodes)");
  std::cmatch m;
  if (std::regex_search(msg, m, kMissing) || std::regex_search(msg, m, kDiscard))
    self->ids.insert(std::strtoll(m[1].first, nullptr, 10));
}

}  // namespace

std::string tag(const Tags& tags, std::string_view key) {
  const auto it = tags.find(key);
  return it == tags.end() ? std::string{} : it->second;
}

OsmData read_osm(const std::filesystem::path& path) {
  GDALAllRegister();
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error(path.string() + ": osm: no such file");
  BrokenWays broken;
  CPLPushErrorHandlerEx(collect, &broken);
  CPLSetThreadLocalConfigOption("CPL_DEBUG", "OSM");
  struct Restore {
    ~Restore() {
      CPLSetThreadLocalConfigOption("CPL_DEBUG", nullptr);
      CPLPopErrorHandler();
    }
  } restore;
  const char* drivers[] = {"OSM", nullptr};
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(path.string().c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, drivers));
  if (!ds)
    throw std::runtime_error(path.string() + ": osm: GDAL's OSM driver cannot read it");
  OsmData out;
  struct Raw {
    std::int64_t id;
    std::string layer;
    std::unique_ptr<OGRFeature> f;
  };
  std::vector<Raw> raw;
  OGRLayer* layer = nullptr;
  while (true) {
    std::unique_ptr<OGRFeature> f(ds->GetNextFeature(&layer, nullptr, nullptr, nullptr));
    if (!f)
      break;
    const std::string name = layer->GetName();
    const int id_field = f->GetFieldIndex(name == "multipolygons" ? "osm_way_id" : "osm_id");
    std::int64_t id = 0;
    if (id_field >= 0 && f->IsFieldSetAndNotNull(id_field))
      id = f->GetFieldAsInteger64(id_field);
    else if (const int rel = f->GetFieldIndex("osm_id"); rel >= 0 && f->IsFieldSetAndNotNull(rel))
      id = f->GetFieldAsInteger64(rel);
    raw.push_back({id, name, std::move(f)});
  }
  // Ways GDAL found broken: dropped whole (areas built from them too).
  for (Raw& r : raw) {
    const OGRGeometry* g = r.f->GetGeometryRef();
    if (g == nullptr || g->IsEmpty())
      continue;
    const bool way_based = r.layer == "lines" ||
                           (r.layer == "multipolygons" && r.f->GetFieldIndex("osm_way_id") >= 0 &&
                            r.f->IsFieldSetAndNotNull(r.f->GetFieldIndex("osm_way_id")));
    if (way_based && broken.ids.count(r.id))
      continue;
    const OGRwkbGeometryType t = wkbFlatten(g->getGeometryType());
    if (r.layer == "points" && t == wkbPoint) {
      const auto* p = g->toPoint();
      out.nodes.push_back(
          {r.id, {common::radians(p->getX()), common::radians(p->getY())}, feature_tags(*r.f)});
    } else if (r.layer == "lines" && t == wkbLineString) {
      out.ways.push_back({r.id, ring_points(*g->toLineString()), feature_tags(*r.f)});
    } else if (r.layer == "multipolygons" && (t == wkbMultiPolygon || t == wkbPolygon)) {
      OsmArea a{r.id, {}, feature_tags(*r.f)};
      auto add = [&](const OGRPolygon& poly) {
        std::vector<std::vector<LonLat>> rings;
        for (const OGRLinearRing* ring : poly)
          rings.push_back(ring_points(*ring));
        if (!rings.empty() && rings[0].size() >= 4)
          a.polygons.push_back(std::move(rings));
      };
      if (t == wkbPolygon)
        add(*g->toPolygon());
      else
        for (const OGRPolygon* poly : *g->toMultiPolygon())
          add(*poly);
      if (!a.polygons.empty())
        out.areas.push_back(std::move(a));
    }
  }
  out.broken_ways = broken.ids.size();
  for (std::int64_t id : broken.ids) {
    if (out.broken_way_ids.size() < 8)
      out.broken_way_ids.push_back(id);
  }
  return out;
}

}  // namespace radar_emu::scene::geodata
