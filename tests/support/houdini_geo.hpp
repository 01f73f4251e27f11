// A reader of the Houdini classic ASCII geometry the `geo` and `geo_gz` exports write, written from
// the format's documentation (sidefx.com/docs/houdini/io/formats/geo.html), not from the writer's
// code: the header, the point attribute dictionary, the points and the particle primitive; and
// gunzip by zlib, for the .geo.gz files.
#pragma once

#include <zlib.h>

#include <cstddef>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace sandflow::test {

struct GeoPoint {
  float P[3];
  std::map<std::string, std::vector<double>> attr;
};

struct GeoAttribute {
  std::string name, type;
  std::vector<double> defaults;
};

struct Geo {
  std::vector<GeoAttribute> dictionary;  ///< the point attributes, in order
  std::vector<GeoPoint> points;
  std::vector<std::size_t> part;  ///< the points of the particle primitive
};

/// The geometry in `text`; throws std::runtime_error naming what is malformed.
inline Geo parse_geo(const std::string& text) {
  std::istringstream in(text);
  std::string w;
  std::size_t npoints = 0, nprims = 0, g1 = 0, g2 = 0, npattr = 0, v = 0, nprattr = 0, na = 0;
  in >> w;
  if (w != "PGEOMETRY") throw std::runtime_error("geo: magic");
  in >> w;  // V5
  in >> w >> npoints >> w >> nprims;
  in >> w >> g1 >> w >> g2;
  in >> w >> npattr >> w >> v >> w >> nprattr >> w >> na;
  if (!in) throw std::runtime_error("geo: bad header");
  Geo g;
  if (npattr > 0) {
    in >> w;
    if (w != "PointAttrib") throw std::runtime_error("geo: no PointAttrib");
    for (std::size_t a = 0; a < npattr; ++a) {
      GeoAttribute at;
      int size = 0;
      in >> at.name >> size >> at.type;
      at.defaults.resize(static_cast<std::size_t>(size));
      for (double& d : at.defaults) in >> d;
      g.dictionary.push_back(at);
    }
  }
  g.points.resize(npoints);
  for (GeoPoint& p : g.points) {
    float wgt;
    in >> p.P[0] >> p.P[1] >> p.P[2] >> wgt;
    char paren = 0;
    in >> paren;
    if (paren != '(') throw std::runtime_error("geo: no (");
    for (const GeoAttribute& a : g.dictionary)
      for (std::size_t k = 0; k < a.defaults.size(); ++k) {
        double x;
        in >> x;
        p.attr[a.name].push_back(x);
      }
    in >> paren;
    if (paren != ')') throw std::runtime_error("geo: no )");
  }
  if (nprims == 1) {
    in >> w;  // PrimitiveAttrib
    std::getline(in, w);
    std::getline(in, w);  // generator 1 index 1 papi
    std::size_t n = 0;
    in >> w >> n;
    if (w != "Part") throw std::runtime_error("geo: no Part");
    g.part.resize(n);
    for (auto& i : g.part) in >> i;
  }
  in >> w;
  if (w == "[0]") in >> w;
  if (w != "beginExtra") throw std::runtime_error("geo: no beginExtra, got " + w);
  return g;
}

/// The bytes of gzip data (one member), by zlib; throws std::runtime_error when it is not.
inline std::string gunzip(const std::string& gz) {
  z_stream zs{};
  if (inflateInit2(&zs, 16 + MAX_WBITS) != Z_OK) throw std::runtime_error("gunzip: no zlib");
  std::string out;
  char buf[1 << 16];
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
  zs.avail_in = static_cast<uInt>(gz.size());
  int rc = Z_OK;
  while (rc == Z_OK) {
    zs.next_out = reinterpret_cast<Bytef*>(buf);
    zs.avail_out = sizeof buf;
    rc = inflate(&zs, Z_NO_FLUSH);
    out.append(buf, sizeof buf - zs.avail_out);
  }
  const bool whole = rc == Z_STREAM_END && zs.avail_in == 0;
  inflateEnd(&zs);
  if (!whole) throw std::runtime_error("gunzip: not one whole gzip member");
  return out;
}

}  // namespace sandflow::test
