// The peer comparison of the mesh readers: each file given is read by sandflow (load_mesh) and by
// assimp as a program would use it alone (every reader registered, ValidateDataStructure,
// Triangulate, JoinIdenticalVertices), and one line says what each made of it. Assimp runs in a
// child process with limits on its time and memory, so that a hang, a crash or an allocation
// without end is a result, not the end of the run (nor of the machine's memory).
// docs/meshes.md ("Which reader reads which format") has the table this printed for the corpus:
//
//   build/bench/compare_mesh_readers tests/data/meshes/*.* tests/data/meshes/bad/*
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <assimp/Importer.hpp>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "geometry/mesh_io.hpp"

namespace {

constexpr int kSecondsAllowed = 10;
constexpr rlim_t kBytesAllowed = rlim_t{2} << 30;

std::string one_line(std::string s, std::size_t keep = 90) {
  for (char& c : s)
    if (c == '\n' || c == '\r' || c == '|') c = ' ';
  return s.size() > keep ? s.substr(0, keep) + "..." : s;
}

std::string with_sandflow(const std::string& path) {
  try {
    const sandflow::TriangleMesh m = sandflow::load_mesh(path);
    return "read: " + std::to_string(m.triangles.size()) + " triangles";
  } catch (const sandflow::InputError& e) {
    std::string msg = e.what();
    if (msg.rfind(path, 0) == 0) msg = msg.substr(path.size());  // (every message starts so)
    return "refused: " + one_line(msg);
  }
}

// In the child: what assimp made of the file, as one line.
std::string with_assimp(const std::string& path) {
  Assimp::Importer importer;
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                  aiProcess_JoinIdenticalVertices);
  if (scene == nullptr) return "refused: " + one_line(importer.GetErrorString());
  std::size_t triangles = 0, not_finite = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) triangles += mesh.mFaces[f].mNumIndices == 3;
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      not_finite += !(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
    }
  }
  return "read: " + std::to_string(triangles) + " triangles" +
         (not_finite ? ", " + std::to_string(not_finite) + " vertices not finite" : "");
}

// Runs with_assimp in a child; a hang past the limit or a signal is the answer.
std::string with_assimp_isolated(const std::string& path) {
  int pipe_fds[2];
  if (::pipe(pipe_fds) != 0) return "(no pipe)";
  const pid_t child = ::fork();
  if (child == 0) {
    ::close(pipe_fds[0]);
    const rlimit memory{kBytesAllowed, kBytesAllowed};
    ::setrlimit(RLIMIT_AS, &memory);
    std::string line = with_assimp(path);
    if (line.find("bad_alloc") != std::string::npos)
      line = "OUT OF MEMORY: its 2 GiB were not enough (" + line + ")";
    (void)!::write(pipe_fds[1], line.data(), line.size());
    ::_exit(0);
  }
  ::close(pipe_fds[1]);
  std::string out;
  pollfd p{pipe_fds[0], POLLIN, 0};
  bool hung = false;
  char buffer[4096];
  while (true) {
    if (::poll(&p, 1, kSecondsAllowed * 1000) == 0) {
      hung = true;
      break;
    }
    const ssize_t n = ::read(pipe_fds[0], buffer, sizeof buffer);
    if (n <= 0) break;
    out.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(pipe_fds[0]);
  if (hung) ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  if (hung) return "HANG: still reading after " + std::to_string(kSecondsAllowed) + " s";
  if (WIFSIGNALED(status)) return "CRASH: " + std::string(::strsignal(WTERMSIG(status)));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: compare_mesh_readers MESH...\n");
    return 2;
  }
  std::printf("| file | sandflow | assimp alone |\n|---|---|---|\n");
  for (int i = 1; i < argc; ++i) {
    const std::string path = argv[i];
    if (!std::filesystem::is_regular_file(path)) continue;
    const std::string name = std::filesystem::path(path).filename().string();
    std::printf("| %s | %s | %s |\n", name.c_str(), with_sandflow(path).c_str(),
                with_assimp_isolated(path).c_str());
    std::fflush(stdout);
  }
  return 0;
}
