// STL (ASCII and binary) and glTF 2.0 (.gltf, .glb) through assimp (libassimp-dev, Debian 12's
// 5.2.5): glTF's reader is large (JSON, base64 and binary buffers, accessors, a node tree), so a
// well-kept library beats writing one here, and STL comes with it. OBJ, PLY and OFF keep their
// own readers: on the malformed-mesh corpus assimp hung on a PLY header, allocated whatever a
// count announced, and read NaN, wrong indices and cut files without a word. FBX and COLLADA are
// not read: a fuzzer took a minute to crash assimp's FBX reader (a model connected to itself
// overflows its stack) and to make its COLLADA reader take 12 GB for a 1 KB file (docs/meshes.md,
// "Which reader reads which format").
//
// What this file adds around assimp, and why:
// - only the readers of the file's format are registered: assimp otherwise hands a file that its
//   reader refuses to whichever of its 60 readers recognises the bytes;
// - the file's bytes come from memory (read, size-checked and inflated by mesh_io.cpp); a file it
//   names (a glTF's .bin) is read from beside it, and only when it is a regular file and all
//   together stay within the size limit;
// - a binary STL's size is checked against its triangle count first: assimp takes a file whose
//   size disagrees for ASCII, or says only that it cannot tell which it is;
// - coordinates are checked finite before vertices are joined (the joining sorts positions, and
//   NaN has no place in a sort);
// - assimp's log never reaches stdout or stderr; what it logs while reading is kept, and refuses
//   the file: its STL and glTF readers log only about data they drop or guess at (a facet of four
//   vertices, faces with indices out of range). (The warnings of assimp's own check of its data,
//   about lights, cameras, materials and animations, are left out.)
//
// Units and axes: coordinates are taken as the file stores them, in metres (glTF's unit by its
// specification; STL states none), and axes as stored: glTF is y-up by its specification, so a
// glTF model stands up with `rotation = [90, 0, 0]` (docs/scenes.md). All meshes of the file are
// merged, each placed by its node's transform.
#include <assimp/BaseImporter.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/MemoryIOWrapper.h>
#include <assimp/config.h>
#include <assimp/importerdesc.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/DefaultLogger.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/file_kind.hpp"
#include "geometry/mesh_io.hpp"
#include "geometry/mesh_io_detail.hpp"

namespace sandflow::mesh_io {

namespace {

namespace fs = std::filesystem;

struct AssimpFormat {
  const char* name;                     ///< for messages: "STL", "glTF"
  std::vector<std::string> extensions;  ///< as assimp lists them, lower case, no dot
};

AssimpFormat assimp_format(MeshFormat format) {
  switch (format) {
    case MeshFormat::Stl:
      return {"STL", {"stl"}};
    case MeshFormat::Gltf:
      return {"glTF", {"gltf", "glb"}};
    default:
      throw std::logic_error("read_with_assimp: not a format read through assimp");
  }
}

// The name assimp is given: the file's own (minus ".gz"), so that the files it names are found
// beside it, ending in an extension of the format, by which assimp picks its reader.
std::string assimp_name(const std::string& file, const AssimpFormat& format) {
  std::string name = file;
  if (lower_case(name).ends_with(".gz")) name.resize(name.size() - 3);
  for (const std::string& ext : format.extensions)
    if (lower_case(name).ends_with("." + ext)) return name;
  return name + "." + format.extensions.front();
}

// Assimp's number parser quotes the rest of the file, its line ends printed as '?': keep the
// quote's first line that has something on it. Any message is kept short.
std::string shortened(std::string message) {
  constexpr std::size_t kMaxChars = 160;
  const std::string quote = "Cannot parse string \"";
  const std::size_t after = message.find("\" as a real number");
  if (message.rfind(quote, 0) == 0 && after != std::string::npos) {
    const std::size_t start = std::min(message.find_first_not_of("? \t", quote.size()), after);
    const std::size_t end = start < after ? message.find('?', start) : after;
    message = quote + message.substr(start, std::min(end, after) - start) + message.substr(after);
  }
  for (char& c : message)
    if (c == '\n' || c == '\r') c = ' ';
  if (message.size() > kMaxChars) message = message.substr(0, kMaxChars) + "...";
  return message;
}

// Where assimp's log goes: nowhere, but its warnings and errors are kept while a file is read.
// Installed once in place of assimp's default logger (which drops everything); reads are
// serialised by assimp_mutex() (Debian builds assimp single-threaded, and its logger is global).
class ProblemCollector final : public Assimp::Logger {
 public:
  std::vector<std::string>* problems = nullptr;

  bool attachStream(Assimp::LogStream*, unsigned int) override { return false; }
  bool detachStream(Assimp::LogStream*, unsigned int) override { return false; }

 private:
  void OnDebug(const char*) override {}
  void OnVerboseDebug(const char*) override {}
  void OnInfo(const char*) override {}
  void OnWarn(const char* message) override {
    // (assimp's check of its own data: lights, cameras, materials, animations)
    if (std::strncmp(message, "Validation warning:", 19) != 0) keep(message);
  }
  void OnError(const char* message) override { keep(message); }
  void keep(const char* message) {
    if (problems) problems->emplace_back(message);
  }
};

std::mutex& assimp_mutex() {
  static std::mutex m;
  return m;
}

ProblemCollector& problem_collector() {
  // (assimp owns it once set, and would delete it only if another logger replaced it)
  static ProblemCollector* const collector = [] {
    auto* c = new ProblemCollector;
    Assimp::DefaultLogger::set(c);
    return c;
  }();
  return *collector;
}

// The files assimp opens: the mesh itself from memory; a file it names (a glTF's buffers) from
// disk, when it is a regular file (never a FIFO, which would block) and all of them together stay
// within the limit for the file itself. Nothing is written. Why a named file was refused is kept:
// assimp would only say that it could not open it.
class MeshFiles final : public Assimp::IOSystem {
 public:
  MeshFiles(std::string_view data, std::string name) : data_(data), name_(std::move(name)) {}

  std::string refusal;  ///< "" or why a named file was not opened

  bool Exists(const char* path) const override {
    std::error_code ec;
    return path == name_ || fs::exists(path, ec);
  }
  char getOsSeparator() const override { return '/'; }

  Assimp::IOStream* Open(const char* path, const char* mode) override {
    if (std::strpbrk(mode, "wa+") != nullptr) return nullptr;
    if (path == name_)
      return new Assimp::MemoryIOStream(reinterpret_cast<const std::uint8_t*>(data_.data()),
                                        data_.size());
    if (const std::string kind = special_file_kind(path); !kind.empty()) {
      refusal = "the file it names, '" + std::string(path) + "', is " + kind + ", not a file";
      return nullptr;
    }
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec) return nullptr;  // (not there: assimp says which file it could not open)
    if (data_.size() + opened_bytes_ + size > kMaxAssimpMeshBytes) {
      refusal = "with the files it names ('" + std::string(path) + "' is " + std::to_string(size) +
                " bytes), more than the limit of " + std::to_string(kMaxAssimpMeshBytes) +
                " bytes for the formats read through assimp";
      return nullptr;
    }
    opened_bytes_ += size;
    return disk_.Open(path, mode);
  }
  void Close(Assimp::IOStream* stream) override { delete stream; }

 private:
  std::string_view data_;
  std::string name_;
  std::uintmax_t opened_bytes_ = 0;
  Assimp::DefaultIOSystem disk_;
};

// Every reader assimp has but those of `format` is taken out, so no other one ever sees the bytes.
void keep_only_readers_of(Assimp::Importer& importer, const AssimpFormat& format) {
  for (std::size_t i = importer.GetImporterCount(); i-- > 0;) {
    Assimp::BaseImporter* reader = importer.GetImporter(i);
    const aiImporterDesc* info = importer.GetImporterInfo(i);
    std::istringstream listed(info != nullptr ? info->mFileExtensions : "");
    bool wanted = false;
    for (std::string ext; listed >> ext;)
      wanted = wanted || std::find(format.extensions.begin(), format.extensions.end(),
                                   lower_case(ext)) != format.extensions.end();
    if (wanted) continue;
    importer.UnregisterLoader(reader);
    delete reader;  // (unregistering hands it back)
  }
}

// Assimp takes an STL for binary when its size is exactly 84 + 50 n bytes (n the count at byte
// 80), else for ASCII when it starts with "solid"; a binary file cut short or with a wrong count is
// then read as ASCII or refused as "cannot determine". An ASCII STL is text: no NUL byte, which
// every binary STL has (the header's padding, a count below 2^24).
void check_stl_layout(std::string_view data, const std::string& file) {
  constexpr std::size_t kHeader = 84, kRecord = 50;
  std::uint32_t count = 0;
  if (data.size() >= kHeader) std::memcpy(&count, data.data() + 80, sizeof count);
  const std::uint64_t expected = kHeader + std::uint64_t{kRecord} * count;
  if (data.size() >= kHeader && data.size() == expected) {
    if (count > kMaxMeshTriangles)
      fail_file(file, "binary STL of " + std::to_string(count) +
                          " triangles, more than the limit of " +
                          std::to_string(kMaxMeshTriangles));
    return;
  }
  const std::size_t start = data.find_first_not_of(" \t\r\n");
  const bool text = data.find('\0') == std::string_view::npos;
  if (text && start != std::string_view::npos && data.substr(start, 5) == "solid") return;
  if (data.size() < kHeader)
    fail_file(file,
              "neither a binary STL (which starts with an 84-byte header: 80 bytes, then "
              "the triangle count; the file has " +
                  std::to_string(data.size()) +
                  " bytes) nor an ASCII STL (which starts with 'solid')");
  fail_file(file, "binary STL: its count at byte 80 announces " + std::to_string(count) +
                      " triangles, which take 84 + 50 x " + std::to_string(count) + " = " +
                      std::to_string(expected) + " bytes, but the file has " +
                      std::to_string(data.size()) + " bytes (" +
                      (data.size() < expected ? "truncated?" : "a wrong count?") + ")");
}

// Why assimp refused a file, as well as can be said: its glTF reader turns a JSON syntax error
// into "no suitable reader", so the JSON is parsed again here for the line and column.
[[noreturn]] void refuse(std::string_view data, const AssimpFormat& f, const std::string& file,
                         const std::string& assimp_message, const char* what) {
  if (assimp_message.rfind("No suitable reader found", 0) == 0) {
    if (f.extensions.front() == "gltf" && data.substr(0, 4) != "glTF") {
      try {
        [[maybe_unused]] const nlohmann::json parsed = nlohmann::json::parse(data);
      } catch (const nlohmann::json::exception& e) {  // (a syntax error, a number out of range)
        fail_file(file, std::string("not valid glTF JSON: ") + e.what());
      }
    }
    fail_file(file, std::string("assimp's ") + f.name +
                        " reader does not recognise the file (it says no more)");
  }
  fail_file(file, std::string("assimp ") + what + " this " + f.name +
                      " file: " + shortened(assimp_message));
}

bool finite(const aiVector3D& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

std::string text(const aiVector3D& v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

// Every vertex as read must be finite: named by its facet in an STL (assimp keeps three vertices a
// facet, in the file's order), by its mesh and index otherwise.
void check_finite_as_read(const aiScene& scene, MeshFormat format, const std::string& file) {
  std::size_t facets_before = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      if (finite(mesh.mVertices[v])) continue;
      if (format == MeshFormat::Stl)
        fail_file(file, "facet " + std::to_string(facets_before + v / 3) + " (counting from 0): " +
                            "vertex " + text(mesh.mVertices[v]) + " is not finite");
      fail_file(file, "mesh '" + std::string(mesh.mName.C_Str()) + "' (" + std::to_string(m) +
                          " of " + std::to_string(scene.mNumMeshes) + "), vertex " +
                          std::to_string(v) + ": " + text(mesh.mVertices[v]) + " is not finite");
    }
    facets_before += mesh.mNumFaces;
  }
}

}  // namespace

TriangleMesh read_with_assimp(std::string_view data, MeshFormat format, const std::string& file) {
  const AssimpFormat f = assimp_format(format);
  if (data.empty()) fail_file(file, "empty file (expected " + std::string(f.name) + ")");
  if (data.size() > kMaxAssimpMeshBytes)
    fail_file(file, "the file is " + std::to_string(data.size()) +
                        " bytes, more than the limit of " + std::to_string(kMaxAssimpMeshBytes) +
                        " for the formats read through assimp (which take up to 18 times a "
                        "file's size in memory); a binary PLY of the same mesh is read with much "
                        "less");
  if (format == MeshFormat::Stl) check_stl_layout(data, file);

  const std::lock_guard<std::mutex> lock(assimp_mutex());
  std::vector<std::string> problems;
  ProblemCollector& collector = problem_collector();
  collector.problems = &problems;
  struct Detach {
    ProblemCollector& c;
    ~Detach() { c.problems = nullptr; }
  } detach{collector};

  Assimp::Importer importer;
  keep_only_readers_of(importer, f);
  const std::string name = assimp_name(file, f);
  auto* files = new MeshFiles(data, name);
  importer.SetIOHandler(files);  // (the importer owns it)
  // an obstacle needs positions and faces only; without normals, vertices that differ by their
  // normal alone (an STL's, one a facet) are joined
  importer.SetPropertyInteger(
      AI_CONFIG_PP_RVC_FLAGS,
      aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_COLORS |
          aiComponent_TEXCOORDS | aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
          aiComponent_TEXTURES | aiComponent_LIGHTS | aiComponent_CAMERAS | aiComponent_MATERIALS);

  // read and check indices and counts (ValidateDataStructure), then the coordinates
  const aiScene* scene = importer.ReadFile(name, aiProcess_ValidateDataStructure);
  if (scene == nullptr && !files->refusal.empty()) fail_file(file, files->refusal);
  if (scene == nullptr) refuse(data, f, file, importer.GetErrorString(), "cannot read");
  if (!problems.empty())
    fail_file(file,
              std::string("malformed ") + f.name + ", assimp says: " + shortened(problems.front()));
  check_finite_as_read(*scene, format, file);

  // one mesh of triangles, each part placed by its node; coordinates checked
  // again (a transform can overflow), then identical vertices joined
  scene = importer.ApplyPostProcessing(aiProcess_RemoveComponent | aiProcess_PreTransformVertices |
                                       aiProcess_Triangulate);
  if (scene == nullptr)
    refuse(data, f, file, importer.GetErrorString(), "could not merge the meshes of");
  for (unsigned m = 0; m < scene->mNumMeshes; ++m)
    for (unsigned v = 0; v < scene->mMeshes[m]->mNumVertices; ++v)
      if (!finite(scene->mMeshes[m]->mVertices[v]))
        fail_file(file, "the file's node transforms take vertex " + std::to_string(v) + " to " +
                            text(scene->mMeshes[m]->mVertices[v]) + ", which is not finite");
  scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices);
  if (scene == nullptr)
    refuse(data, f, file, importer.GetErrorString(), "could not join the vertices of");

  // points and lines are not surfaces: only triangles are kept
  TriangleMesh out;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    const auto first = static_cast<std::uint32_t>(out.vertices.size());
    if (out.vertices.size() + mesh.mNumVertices > kMaxMeshVertices)
      fail_file(file, "more than the limit of " + std::to_string(kMaxMeshVertices) + " vertices");
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      out.vertices.push_back(Vec3{p.x, p.y, p.z});
    }
    for (unsigned k = 0; k < mesh.mNumFaces; ++k) {
      const aiFace& face = mesh.mFaces[k];
      if (face.mNumIndices != 3) continue;
      if (out.triangles.size() >= kMaxMeshTriangles)
        fail_file(file,
                  "more than the limit of " + std::to_string(kMaxMeshTriangles) + " triangles");
      out.triangles.push_back(
          {first + face.mIndices[0], first + face.mIndices[1], first + face.mIndices[2]});
    }
  }

  return out;
}

}  // namespace sandflow::mesh_io

// For the sanitizer and fuzzing builds (LeakSanitizer asks the program for its suppressions
// through this hook; other builds never call it): assimp 5.2.5 leaks what one of its readers had
// built when it throws on a malformed file, such as the mesh and node of the solid it was reading
// in an ASCII STL (2,464 bytes). A refused mesh ends the run, so nothing accumulates. The module
// is named, not a function: libassimp keeps no frame pointers, and the fast unwinder stops in it.
extern "C" const char* __lsan_default_suppressions() {
  return "leak:libassimp.so\n";
}
