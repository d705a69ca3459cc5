// X3P (ISO 5436-2, the openGPS XML schema): a zip archive (libzip) holding main.xml
// (pugixml), the point data (bindata/data.bin) and md5checksum.hex (MD5 by nettle).
// Lengths in the file are metres; trochomill's are mm (texture.hpp).
#include <fmt/format.h>
#include <nettle/md5.h>
#include <zip.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <memory>
#include <pugixml.hpp>
#include <sstream>

#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/texture.hpp"

static_assert(std::endian::native == std::endian::little,
              "X3P binary data is little-endian; this build assumes a little-endian machine");

namespace trochomill {

namespace {

constexpr const char* kNamespace = "http://www.opengps.eu/2008/ISO5436_2";
constexpr const char* kData = "bindata/data.bin";
// The largest map read or written: 2^28 points (2 GB of doubles).
constexpr double kMaxPoints = 268435456.0;
constexpr std::uint64_t kMaxXmlBytes = 256ull << 20;

std::string hex_digest(md5_ctx& ctx) {
  std::uint8_t digest[MD5_DIGEST_SIZE];
  md5_digest(&ctx, MD5_DIGEST_SIZE, digest);
  std::string hex;
  for (const std::uint8_t b : digest) hex += fmt::format("{:02x}", b);
  return hex;
}

std::string md5_hex(const void* data, std::size_t size) {
  md5_ctx ctx;
  md5_init(&ctx);
  md5_update(&ctx, size, static_cast<const std::uint8_t*>(data));
  return hex_digest(ctx);
}

// The point data: the heights in metres (little-endian doubles), made as they are read, for
// the digest and for the archive (libzip reads them through `read_data`): a large map is never
// held twice.
struct PointData {
  const std::vector<double>* z_mm = nullptr;
  std::uint64_t at = 0;  // the next byte libzip reads
  zip_error_t error{};
  [[nodiscard]] std::uint64_t bytes() const { return z_mm->size() * sizeof(double); }
  // Bytes [from, from + n) of the data into `out`.
  void copy(std::uint64_t from, std::uint64_t n, std::uint8_t* out) const {
    while (n > 0) {
      const double m = (*z_mm)[from / sizeof(double)] / 1000.0;
      std::uint8_t b[sizeof(double)];
      std::memcpy(b, &m, sizeof m);
      const std::uint64_t off = from % sizeof(double);
      const std::uint64_t k = std::min<std::uint64_t>(sizeof(double) - off, n);
      std::memcpy(out, b + off, k);
      out += k, from += k, n -= k;
    }
  }
  [[nodiscard]] std::string md5() const {
    md5_ctx ctx;
    md5_init(&ctx);
    std::vector<std::uint8_t> block(1 << 16);
    for (std::uint64_t from = 0; from < bytes(); from += block.size()) {
      const std::uint64_t n = std::min<std::uint64_t>(block.size(), bytes() - from);
      copy(from, n, block.data());
      md5_update(&ctx, n, block.data());
    }
    return hex_digest(ctx);
  }
};

// libzip's source callback over PointData.
zip_int64_t read_data(void* state, void* buf, zip_uint64_t len, zip_source_cmd_t cmd) {
  auto* d = static_cast<PointData*>(state);
  switch (cmd) {
    case ZIP_SOURCE_OPEN:
      d->at = 0;
      return 0;
    case ZIP_SOURCE_READ: {
      const std::uint64_t n = std::min<std::uint64_t>(len, d->bytes() - d->at);
      d->copy(d->at, n, static_cast<std::uint8_t*>(buf));
      d->at += n;
      return static_cast<zip_int64_t>(n);
    }
    case ZIP_SOURCE_CLOSE:
    case ZIP_SOURCE_FREE:
      return 0;
    case ZIP_SOURCE_STAT: {
      auto* st = static_cast<zip_stat_t*>(buf);
      zip_stat_init(st);
      st->size = d->bytes();
      st->valid |= ZIP_STAT_SIZE;
      return sizeof(zip_stat_t);
    }
    case ZIP_SOURCE_ERROR:
      return zip_error_to_data(&d->error, buf, len);
    case ZIP_SOURCE_SUPPORTS:
      return zip_source_make_command_bitmap(ZIP_SOURCE_OPEN, ZIP_SOURCE_READ, ZIP_SOURCE_CLOSE,
                                            ZIP_SOURCE_STAT, ZIP_SOURCE_ERROR, ZIP_SOURCE_FREE, -1);
    default:
      zip_error_set(&d->error, ZIP_ER_OPNOTSUPP, 0);
      return -1;
  }
}

std::string utc_date() {
  std::time_t t = std::time(nullptr);
  if (const char* e = std::getenv("SOURCE_DATE_EPOCH"); e != nullptr && *e != '\0') {
    long long v = 0;
    const auto [p, ec] = std::from_chars(e, e + std::strlen(e), v);
    if (ec == std::errc() && *p == '\0' && v >= 0) t = static_cast<std::time_t>(v);
  }
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[40];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S+00:00", &tm);
  return buf;
}

// A length in mm as metres, shortest round-trip decimal (mm / 1000 then back * 1000 is the
// same mm for the lengths written here: checked by the round-trip test).
std::string metres(double mm) { return fmt::format("{}", mm / 1000.0); }

struct ZipCloser {
  void operator()(zip_t* z) const { zip_discard(z); }
};
using Zip = std::unique_ptr<zip_t, ZipCloser>;

std::string zip_error_text(int code) {
  zip_error_t e;
  zip_error_init_with_code(&e, code);
  std::string s = zip_error_strerror(&e);
  zip_error_fini(&e);
  return s;
}

}  // namespace

void write_x3p(const std::filesystem::path& file, const HeightMap& map, const X3pInfo& info) {
  if (map.ny == 1) {  // a profile: check it as a map of two identical rows
    HeightMap two = map;
    two.ny = 2;
    two.dy_mm = map.dx_mm;
    two.z_mm.insert(two.z_mm.end(), map.z_mm.begin(), map.z_mm.end());
    check_height_map(two, "X3P");
  } else {
    check_height_map(map, "X3P");
  }
  if (static_cast<double>(map.nx) * static_cast<double>(map.ny) > kMaxPoints) {
    throw InputError(fmt::format("X3P: {} x {} points is past the limit of 2^28", map.nx, map.ny));
  }
  PointData data;
  data.z_mm = &map.z_mm;
  zip_error_init(&data.error);

  pugi::xml_document doc;
  auto decl = doc.append_child(pugi::node_declaration);
  decl.append_attribute("version") = "1.0";
  decl.append_attribute("encoding") = "UTF-8";
  auto root = doc.append_child("p:ISO5436_2");
  root.append_attribute("xmlns:p") = kNamespace;
  auto text = [](pugi::xml_node parent, const char* name, const std::string& value) {
    parent.append_child(name).text().set(value.c_str());
    return parent;
  };
  auto r1 = root.append_child("Record1");
  text(r1, "Revision", "ISO5436 - 2000");
  text(r1, "FeatureType", map.ny == 1 ? "PRF" : "SUR");
  auto axes = r1.append_child("Axes");
  for (const auto& [name, inc, off] :
       {std::tuple{"CX", map.dx_mm, map.x0_mm},
        std::tuple{"CY", map.ny == 1 ? map.dx_mm : map.dy_mm, map.y0_mm}}) {
    auto c = axes.append_child(name);
    text(c, "AxisType", "I");
    text(c, "DataType", "D");
    text(c, "Increment", metres(inc));
    text(c, "Offset", metres(off));
  }
  auto cz = axes.append_child("CZ");
  text(cz, "AxisType", "A");
  text(cz, "DataType", "D");
  text(cz, "Increment", "1");
  text(cz, "Offset", "0");
  auto r2 = root.append_child("Record2");
  text(r2, "Date", info.date.empty() ? utc_date() : info.date);
  if (!info.creator.empty()) text(r2, "Creator", info.creator);
  auto inst = r2.append_child("Instrument");
  text(inst, "Manufacturer", info.manufacturer);
  text(inst, "Model", info.model.empty() ? "-" : info.model);
  text(inst, "Serial", info.serial.empty() ? "-" : info.serial);
  text(inst, "Version", info.version.empty() ? "-" : info.version);
  text(r2, "CalibrationDate", info.date.empty() ? utc_date() : info.date);
  auto probe = r2.append_child("ProbingSystem");
  text(probe, "Type", info.probing);
  text(probe, "Identification", "-");
  const std::string comment = info.comment.empty() ? map.description : info.comment;
  if (!comment.empty()) text(r2, "Comment", comment);
  auto r3 = root.append_child("Record3");
  auto dim = r3.append_child("MatrixDimension");
  text(dim, "SizeX", std::to_string(map.nx));
  text(dim, "SizeY", std::to_string(map.ny));
  text(dim, "SizeZ", "1");
  auto link = r3.append_child("DataLink");
  text(link, "PointDataLink", kData);
  text(link, "MD5ChecksumPointData", data.md5());
  text(root.append_child("Record4"), "ChecksumFile", "md5checksum.hex");
  std::ostringstream xml;
  doc.save(xml, "  ", pugi::format_default, pugi::encoding_utf8);
  const std::string main_xml = xml.str();
  const std::string checksum = md5_hex(main_xml.data(), main_xml.size()) + " *main.xml\n";

  int err = 0;
  Zip z(zip_open(file.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err));
  if (!z) {
    throw IoError(fmt::format("cannot write '{}': {}", file.string(), zip_error_text(err)));
  }
  auto add = [&](const char* name, zip_source_t* src) {
    if (src == nullptr)
      throw IoError(fmt::format("'{}': {}", file.string(), zip_strerror(z.get())));
    const zip_int64_t idx = zip_file_add(z.get(), name, src, ZIP_FL_ENC_UTF_8 | ZIP_FL_OVERWRITE);
    if (idx < 0) {
      zip_source_free(src);
      throw IoError(fmt::format("'{}': {}", file.string(), zip_strerror(z.get())));
    }
    // A fixed time stamp: the same map gives the same archive.
    zip_file_set_mtime(z.get(), static_cast<zip_uint64_t>(idx), 315532800, 0);  // 1980-01-01
  };
  add("main.xml", zip_source_buffer(z.get(), main_xml.data(), main_xml.size(), 0));
  add(kData, zip_source_function(z.get(), read_data, &data));
  add("md5checksum.hex", zip_source_buffer(z.get(), checksum.data(), checksum.size(), 0));
  if (zip_close(z.get()) != 0) {
    const std::string why = zip_strerror(z.get());
    zip_error_fini(&data.error);
    throw IoError(fmt::format("cannot write '{}': {}", file.string(), why));
  }
  (void)z.release();  // closed: nothing to discard
  zip_error_fini(&data.error);
}

namespace {

// The reader's context: the file, main.xml's text (for line:column) and helpers that name
// what is wrong.
class X3pReader {
 public:
  X3pReader(std::filesystem::path file, double max_points)
      : file_(std::move(file)), max_points_(max_points) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("{}: {}", file_.string(), what));
  }
  [[noreturn]] void fail_at(pugi::xml_node n, const std::string& what) const {
    // pugixml's offset is the element's name: the column of its '<' reads better.
    auto at = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, n.offset_debug()));
    if (at > 0 && at <= xml_.size() && xml_[at - 1] == '<') --at;
    const auto [line, col] = line_col(at);
    throw InputError(fmt::format("{}:main.xml:{}:{}: {}", file_.string(), line, col, what));
  }
  std::pair<std::size_t, std::size_t> line_col(std::size_t offset) const {
    std::size_t line = 1, col = 1;
    for (std::size_t i = 0; i < offset && i < xml_.size(); ++i) {
      if (xml_[i] == '\n') {
        ++line, col = 1;
      } else {
        ++col;
      }
    }
    return {line, col};
  }

  void open() {
    int err = 0;
    z_.reset(zip_open(file_.c_str(), ZIP_RDONLY | ZIP_CHECKCONS, &err));
    if (!z_) {
      if (err == ZIP_ER_OPEN || err == ZIP_ER_READ || err == ZIP_ER_NOENT) {
        throw InputError(fmt::format("cannot read '{}': {}", file_.string(), zip_error_text(err)));
      }
      fail(fmt::format("not an X3P file: the zip archive cannot be opened ({})",
                       zip_error_text(err)));
    }
  }

  // An entry of the archive, at most `limit` bytes (its stated size is checked first).
  std::string entry(const std::string& name, std::uint64_t limit) const {
    const zip_int64_t idx = zip_name_locate(z_.get(), name.c_str(), 0);
    if (idx < 0) fail(fmt::format("the archive has no '{}'", name));
    zip_stat_t st;
    zip_stat_init(&st);
    if (zip_stat_index(z_.get(), static_cast<zip_uint64_t>(idx), 0, &st) != 0 ||
        (st.valid & ZIP_STAT_SIZE) == 0) {
      fail(fmt::format("'{}' in the archive: {}", name, zip_strerror(z_.get())));
    }
    if (st.size > limit) {
      fail(fmt::format("'{}' in the archive is {} bytes, more than the {} expected", name, st.size,
                       limit));
    }
    zip_file_t* f = zip_fopen_index(z_.get(), static_cast<zip_uint64_t>(idx), 0);
    if (f == nullptr) fail(fmt::format("'{}' in the archive: {}", name, zip_strerror(z_.get())));
    std::string out(st.size, '\0');
    const zip_int64_t got = zip_fread(f, out.data(), st.size);
    const std::string why = got < 0 ? zip_file_strerror(f) : "";
    zip_fclose(f);
    if (got < 0 || static_cast<zip_uint64_t>(got) != st.size) {
      fail(
          fmt::format("'{}' in the archive cannot be read{}", name, why.empty() ? "" : ": " + why));
    }
    return out;
  }

  void parse_xml() {
    xml_ = entry("main.xml", kMaxXmlBytes);
    const pugi::xml_parse_result r =
        doc_.load_buffer(xml_.data(), xml_.size(), pugi::parse_default, pugi::encoding_auto);
    if (!r) {
      const auto [line, col] =
          line_col(static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, r.offset)));
      throw InputError(fmt::format("{}:main.xml:{}:{}: malformed XML: {}", file_.string(), line,
                                   col, r.description()));
    }
    root_ = doc_.document_element();
    if (local(root_.name()) != "ISO5436_2") {
      fail_at(root_, fmt::format("the root element is <{}>, not <ISO5436_2>", root_.name()));
    }
  }

  static std::string_view local(std::string_view name) {
    const auto c = name.find(':');
    return c == std::string_view::npos ? name : name.substr(c + 1);
  }
  // The child of `n` named `name` (any namespace prefix), or a failure naming the path.
  pugi::xml_node child(pugi::xml_node n, std::string_view name, bool required = true) const {
    for (pugi::xml_node c : n.children()) {
      if (c.type() == pugi::node_element && local(c.name()) == name) return c;
    }
    if (required) fail_at(n, fmt::format("<{}> has no <{}>", local(n.name()), name));
    return {};
  }
  std::string text(pugi::xml_node n) const { return trim(n.text().get(), " \t\r\n"); }

  // A number in the XML; lengths in metres become mm by moving the decimal exponent (the
  // decimal text converted once: 5e-06 m reads as exactly the double nearest 0.005 mm).
  double number(pugi::xml_node n, bool metres_to_mm) const {
    std::string s = text(n);
    if (metres_to_mm) {
      const auto e = s.find_first_of("eE");
      long long exp = 0;
      if (e != std::string::npos) {
        const char* b = s.data() + e + 1;
        const char* end = s.data() + s.size();
        if (b != end && *b == '+') ++b;
        const auto [p, ec] = std::from_chars(b, end, exp);
        if (ec != std::errc() || p != end || std::llabs(exp) > 10000) exp = 1 << 20;  // fails below
        s.resize(e);
      }
      s += fmt::format("e{}", exp + 3);
    }
    double v = 0;
    const char* b = s.data();
    if (!s.empty() && s[0] == '+') ++b;
    const auto [p, ec] = std::from_chars(b, s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v) ||
        std::abs(v) > 1e9) {
      fail_at(n, fmt::format("<{}> '{}' is not a number (finite, at most 1e6 m)", local(n.name()),
                             text(n)));
    }
    return v;
  }
  std::size_t count(pugi::xml_node n) const {
    const std::string s = text(n);
    unsigned long long v = 0;
    const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v < 1 ||
        static_cast<double>(v) > kMaxPoints) {
      fail_at(n, fmt::format("<{}> '{}' is not a count from 1 to 2^28", local(n.name()), s));
    }
    return static_cast<std::size_t>(v);
  }

  HeightMap read(X3pInfo* info) {
    open();
    parse_xml();
    const auto r1 = child(root_, "Record1");
    const auto feature = child(r1, "FeatureType");
    const std::string type = text(feature);
    if (type != "SUR" && type != "PRF") {
      fail_at(feature, fmt::format("FeatureType '{}': trochomill reads SUR (a surface) and PRF (a "
                                   "profile); a point cloud (PCL) has no grid",
                                   type));
    }
    const auto axes = child(r1, "Axes");
    HeightMap m;
    for (const auto& [name, inc, off] :
         {std::tuple{"CX", &m.dx_mm, &m.x0_mm}, std::tuple{"CY", &m.dy_mm, &m.y0_mm}}) {
      const auto c = child(axes, name);
      const auto at = child(c, "AxisType");
      if (text(at) != "I") {
        fail_at(at, fmt::format("{} AxisType '{}': only incremental axes (I) are read; absolute "
                                "ones (A) list a coordinate per point",
                                name, text(at)));
      }
      const auto in = child(c, "Increment");
      *inc = number(in, true);
      if (!(*inc > 0)) fail_at(in, fmt::format("{} Increment must be > 0 m", name));
      const auto o = child(c, "Offset", false);
      *off = o ? number(o, true) : 0.0;
    }
    const auto cz = child(axes, "CZ");
    const auto dt = child(cz, "DataType");
    const std::string ztype = text(dt);
    std::size_t size = 0;
    if (ztype == "I") {
      size = 2;
    } else if (ztype == "L" || ztype == "F") {
      size = 4;
    } else if (ztype == "D") {
      size = 8;
    } else {
      fail_at(dt, fmt::format("CZ DataType '{}': I (int16), L (int32), F (float) or D (double)",
                              ztype));
    }
    const auto zi = child(cz, "Increment", false), zo = child(cz, "Offset", false);
    // z (mm) = raw * scale + offset: the scale is CZ's increment (metres) in mm.
    const double scale = zi ? number(zi, true) : 1e3;
    const double offset = zo ? number(zo, true) : 0.0;
    if (zi && !(scale != 0)) fail_at(zi, "CZ Increment must not be 0");

    const auto r3 = child(root_, "Record3");
    const auto dim = child(r3, "MatrixDimension");
    m.nx = count(child(dim, "SizeX"));
    m.ny = count(child(dim, "SizeY"));
    const auto sz = child(dim, "SizeZ");
    if (count(sz) != 1) {
      fail_at(sz, fmt::format("SizeZ {}: several layers per point are not read (1 expected)",
                              text(sz)));
    }
    if (static_cast<double>(m.nx) * static_cast<double>(m.ny) > max_points_) {
      fail_at(dim, fmt::format("{} x {} points is past the limit of {:.4g} points{}", m.nx, m.ny,
                               max_points_,
                               max_points_ < kMaxPoints ? " (the memory limit)" : " (2^28)"));
    }
    if (type == "PRF" && m.ny != 1) fail_at(dim, "a profile (PRF) has SizeY 1");
    const std::size_t n = m.nx * m.ny;
    std::vector<double> raw(n);
    if (const auto link = child(r3, "DataLink", false)) {
      const auto pl = child(link, "PointDataLink");
      const std::string name = text(pl);
      const std::string bin = entry(name, static_cast<std::uint64_t>(n) * size);
      if (bin.size() != n * size) {
        fail_at(pl, fmt::format("'{}' holds {} bytes; {} x {} points of {} bytes need {}", name,
                                bin.size(), m.nx, m.ny, size, n * size));
      }
      if (const auto sum = child(link, "MD5ChecksumPointData", false)) {
        std::string want = text(sum);
        std::transform(want.begin(), want.end(), want.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (md5_hex(bin.data(), bin.size()) != want) {
          fail_at(sum,
                  fmt::format("'{}' does not match its MD5 checksum: the file is damaged", name));
        }
      }
      if (child(link, "ValidPointsLink", false)) {
        const std::string valid = entry(text(child(link, "ValidPointsLink")), (n + 7) / 8);
        for (std::size_t i = 0; i < n; ++i) {
          if (i / 8 >= valid.size() ||
              (static_cast<unsigned char>(valid[i / 8]) & (1u << (i % 8))) == 0) {
            fail(
                fmt::format("point {} (column {}, row {}) is marked invalid: trochomill needs "
                            "complete maps (fill the missing points in the instrument's "
                            "software)",
                            i, i % m.nx, i / m.nx));
          }
        }
      }
      const char* p = bin.data();
      for (std::size_t i = 0; i < n; ++i, p += size) {
        if (ztype == "I") {
          std::int16_t v;
          std::memcpy(&v, p, 2);
          raw[i] = v;
        } else if (ztype == "L") {
          std::int32_t v;
          std::memcpy(&v, p, 4);
          raw[i] = v;
        } else if (ztype == "F") {
          float v;
          std::memcpy(&v, p, 4);
          raw[i] = v;
        } else {
          std::memcpy(&raw[i], p, 8);
        }
      }
    } else {
      const auto list = child(r3, "DataList", false);
      if (!list) fail_at(r3, "<Record3> has neither <DataLink> nor <DataList>");
      std::size_t i = 0;
      for (pugi::xml_node d : list.children()) {
        if (d.type() != pugi::node_element) continue;
        if (i == n)
          fail_at(d, fmt::format("<DataList> holds more than {} x {} points", m.nx, m.ny));
        const std::string s = text(d);
        if (s.empty()) {
          fail(
              fmt::format("point {} (column {}, row {}) is empty (invalid): trochomill needs "
                          "complete maps",
                          i, i % m.nx, i / m.nx));
        }
        raw[i++] = number(d, false);
      }
      if (i != n)
        fail_at(list, fmt::format("<DataList> holds {} of {} x {} points", i, m.nx, m.ny));
    }
    m.z_mm.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      m.z_mm[i] = raw[i] * scale + offset;
      if (!std::isfinite(m.z_mm[i]) || std::abs(m.z_mm[i]) > 1e9) {
        fail(fmt::format(
            "point {} (column {}, row {}) is {}: trochomill needs complete maps of "
            "finite heights",
            i, i % m.nx, i / m.nx, std::isnan(raw[i]) ? "not measured (NaN)" : "not finite"));
      }
    }
    X3pInfo got;
    if (const auto r2 = child(root_, "Record2", false)) {
      auto field = [&](pugi::xml_node parent, const char* name) {
        const auto c = child(parent, name, false);
        return c ? text(c) : std::string();
      };
      got.date = field(r2, "Date");
      got.creator = field(r2, "Creator");
      if (const auto inst = child(r2, "Instrument", false)) {
        got.manufacturer = field(inst, "Manufacturer");
        got.model = field(inst, "Model");
        got.serial = field(inst, "Serial");
        got.version = field(inst, "Version");
      }
      if (const auto probe = child(r2, "ProbingSystem", false)) got.probing = field(probe, "Type");
      got.comment = field(r2, "Comment");
    } else {
      got.manufacturer.clear();
    }
    m.description =
        fmt::format("X3P {}, {} x {} points every {:g} x {:g} um{}{}",
                    type == "PRF" ? "profile" : "surface", m.nx, m.ny, 1000 * m.dx_mm,
                    1000 * m.dy_mm, got.manufacturer.empty() ? "" : ", " + got.manufacturer,
                    got.model.empty() ? "" : " " + got.model);
    if (info != nullptr) *info = got;
    return m;
  }

 private:
  std::filesystem::path file_;
  double max_points_;
  Zip z_;
  std::string xml_;
  pugi::xml_document doc_;
  pugi::xml_node root_;
};

}  // namespace

HeightMap read_x3p(const std::filesystem::path& file, X3pInfo* info, double max_points) {
  X3pReader r(file, std::min(max_points, kMaxPoints));
  return r.read(info);
}

}  // namespace trochomill
