#include "importers/assimp_snapshot.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>
#include <assimp/Importer.hpp>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>
#include <thread>
#include <unordered_set>

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/assimp_guards.hpp"
#include "importers/memory_budget.hpp"

#if defined(__SANITIZE_ADDRESS__)
#define SOFTBAKE_ADDRESS_SANITIZER 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define SOFTBAKE_ADDRESS_SANITIZER 1
#endif
#endif
#ifndef SOFTBAKE_ADDRESS_SANITIZER
#define SOFTBAKE_ADDRESS_SANITIZER 0
#endif
#if SOFTBAKE_ADDRESS_SANITIZER
#include <sanitizer/asan_interface.h>
#endif

namespace softbake {

namespace {

// ---- reading the scene -------------------------------------------------------------------------

std::uint64_t vertexCount(const aiScene& scene) {
  std::uint64_t vertices = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) vertices += scene.mMeshes[m]->mNumVertices;
  return vertices;
}

std::uint64_t faceCount(const aiScene& scene) {
  std::uint64_t faces = 0;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) faces += scene.mMeshes[m]->mNumFaces;
  return faces;
}

// Vertices of the file's meshes that no face uses, as the loader returned them: post-processing
// could split them off or drop them.
std::uint64_t unusedVertices(const aiScene& scene) {
  std::uint64_t unused = 0;
  std::vector<char> used;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& mesh = *scene.mMeshes[m];
    used.assign(mesh.mNumVertices, 0);
    for (unsigned f = 0; f < mesh.mNumFaces; ++f)
      for (unsigned i = 0; i < mesh.mFaces[f].mNumIndices; ++i)
        if (mesh.mFaces[f].mIndices[i] < mesh.mNumVertices) used[mesh.mFaces[f].mIndices[i]] = 1;
    unused += std::uint64_t(std::count(used.begin(), used.end(), 0));
  }
  return unused;
}

SnapshotMesh copyMesh(const aiMesh& source) {
  SnapshotMesh mesh;
  mesh.name = source.mName.C_Str();
  mesh.triangles.reserve(source.mNumFaces);
  for (unsigned f = 0; f < source.mNumFaces; ++f) {
    const aiFace& face = source.mFaces[f];
    if (face.mNumIndices == 3)
      mesh.triangles.push_back({face.mIndices[0], face.mIndices[1], face.mIndices[2]});
    else if (face.mNumIndices == 1)
      ++mesh.points;
    else
      ++mesh.lines;
  }
  mesh.positions.resize(source.mNumVertices);
  for (unsigned v = 0; v < source.mNumVertices; ++v) {
    const aiVector3D& p = source.mVertices[v];
    mesh.positions[v] = Vec3f(p.x, p.y, p.z);
  }
  if (source.HasNormals()) {
    mesh.normals.resize(source.mNumVertices);
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      const aiVector3D& n = source.mNormals[v];
      mesh.normals[v] = Vec3f(n.x, n.y, n.z);
    }
  }
  if (source.HasTextureCoords(0)) {
    mesh.uvs.resize(source.mNumVertices);
    for (unsigned v = 0; v < source.mNumVertices; ++v) {
      const aiVector3D& uv = source.mTextureCoords[0][v];
      mesh.uvs[v] = Vec2f(uv.x, uv.y);
    }
  }
  return mesh;
}

SnapshotNode copyNode(const aiNode& source) {
  SnapshotNode node;
  node.name = source.mName.C_Str();
  const aiMatrix4x4& m = source.mTransformation;
  node.transform << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1,
      m.d2, m.d3, m.d4;
  node.meshes.assign(source.mMeshes, source.mMeshes + source.mNumMeshes);
  return node;
}

// Without recursion, since node depth comes from the file; a node met twice is copied once.
std::vector<SnapshotNode> copyNodes(const aiNode* root) {
  std::vector<SnapshotNode> nodes;
  if (!root) return nodes;
  std::unordered_set<const aiNode*> seen = {root};
  std::vector<std::pair<const aiNode*, std::uint32_t>> stack = {{root, 0}};
  nodes.push_back(copyNode(*root));
  while (!stack.empty()) {
    const auto [node, index] = stack.back();
    stack.pop_back();
    for (unsigned c = 0; c < node->mNumChildren; ++c) {
      const aiNode* child = node->mChildren[c];
      if (!child || !seen.insert(child).second) continue;
      const auto childIndex = std::uint32_t(nodes.size());
      nodes[index].children.push_back(childIndex);
      nodes.push_back(copyNode(*child));
      stack.emplace_back(child, childIndex);
    }
  }
  return nodes;
}

// ---- the byte form -----------------------------------------------------------------------------

// Every value goes as its bytes: both ends are the same program on the same machine.
class Writer {
 public:
  explicit Writer(int fd) : fd_(fd) {}
  ~Writer() { flush(); }

  void bytes(const void* data, std::size_t size) {
    const char* p = static_cast<const char*>(data);
    while (size > 0 && ok_) {
      const std::size_t room = std::min(size, kBuffer - used_);
      std::memcpy(buffer_ + used_, p, room);
      used_ += room;
      p += room;
      size -= room;
      if (used_ == kBuffer) flush();
    }
  }
  void number(std::uint64_t value) { bytes(&value, sizeof value); }
  void text(const std::string& value) {
    number(value.size());
    bytes(value.data(), value.size());
  }
  // Plain values: numbers, Eigen's fixed-size vectors and matrices, std::array.
  template <class T>
  void values(const std::vector<T>& items) {
    number(items.size());
    bytes(items.data(), items.size() * sizeof(T));
  }
  bool flush() {
    for (std::size_t done = 0; ok_ && done < used_;) {
      const ssize_t wrote = ::write(fd_, buffer_ + done, used_ - done);
      if (wrote < 0 && errno == EINTR) continue;
      if (wrote <= 0)
        ok_ = false;
      else
        done += std::size_t(wrote);
    }
    used_ = 0;
    return ok_;
  }

 private:
  static constexpr std::size_t kBuffer = 1 << 16;
  int fd_;
  char buffer_[kBuffer];
  std::size_t used_ = 0;
  bool ok_ = true;
};

using Clock = std::chrono::steady_clock;

// What Reader throws when its deadline passes before the bytes came: not a std::exception, so
// that no handler of broken answers takes it for one.
struct AnswerTimedOut {};

class Reader {
 public:
  /// `deadline`: when to give up waiting for bytes (AnswerTimedOut); Clock::time_point::max():
  /// never.
  explicit Reader(int fd, Clock::time_point deadline = Clock::time_point::max())
      : fd_(fd), deadline_(deadline) {}

  void bytes(void* data, std::size_t size) {
    char* p = static_cast<char*>(data);
    while (size > 0) {
      waitForBytes();
      const ssize_t got = ::read(fd_, p, size);
      if (got < 0 && errno == EINTR) continue;
      if (got < 0) throw std::runtime_error(cat("read failed: ", std::strerror(errno)));
      if (got == 0) throw std::runtime_error("the answer ends early");
      p += got;
      size -= std::size_t(got);
    }
  }
  std::uint64_t number() {
    std::uint64_t value = 0;
    bytes(&value, sizeof value);
    return value;
  }
  std::string text() {
    std::string value;
    readGrowing(value);
    return value;
  }
  template <class T>
  std::vector<T> values() {
    std::vector<T> items;
    readGrowing(items);
    return items;
  }

 private:
  // In slices, so a length that the stream does not back up ends at its end instead of in one
  // huge allocation.
  template <class Container>
  void readGrowing(Container& items) {
    using T = typename Container::value_type;
    std::uint64_t left = number();
    constexpr std::uint64_t kSlice = (1 << 20) / sizeof(T) + 1;
    while (left > 0) {
      const std::size_t slice = std::size_t(std::min(left, kSlice));
      const std::size_t old = items.size();
      items.resize(old + slice);
      bytes(items.data() + old, slice * sizeof(T));
      left -= slice;
    }
  }

  // Returns when a read() will not block: there are bytes, or the writer is gone.
  void waitForBytes() const {
    if (deadline_ == Clock::time_point::max()) return;
    for (;;) {
      const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline_ - Clock::now());
      if (left.count() <= 0) throw AnswerTimedOut();
      pollfd ready = {fd_, POLLIN, 0};
      // A minute at most per wait: poll() takes an int of milliseconds.
      const int got = ::poll(&ready, 1, int(std::min<std::int64_t>(left.count(), 60'000)));
      if (got > 0) return;
      if (got < 0 && errno != EINTR)
        throw std::runtime_error(cat("waiting for the answer failed: ", std::strerror(errno)));
    }
  }

  int fd_;
  Clock::time_point deadline_;
};

// ThreadSanitizer's runtime in GCC 12 does not hold its allocator's locks across fork(), so the
// child of a process with other threads can deadlock in its first malloc when one of them was
// allocating at that moment (llvm-project pull request 96600, fixed in 2024; CI saw it hang). A
// TSan build reads in-process: it checks the threads' message routing, not crash isolation.
#if defined(__SANITIZE_THREAD__)
constexpr bool kThreadSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
constexpr bool kThreadSanitizer = true;
#else
constexpr bool kThreadSanitizer = false;
#endif
#else
constexpr bool kThreadSanitizer = false;
#endif

// The first bytes of every answer: a child that died before writing them sent nothing.
constexpr std::uint64_t kMagic = 0x736f667462616b65;  // "softbake"

// The status of a child whose reading ran out of memory (std::bad_alloc reached it).
constexpr int kOutOfMemoryStatus = 4;

// ---- the child's limits ------------------------------------------------------------------------

// A page the child and the parent share: the child marks on it that an allocation failed, and the
// parent reads it however the child ended (an answer, std::bad_alloc, a crash after a failed
// allocation, or AddressSanitizer's report of one).
struct ChildMarks {
  std::atomic<int> allocationFailed{0};
};
static_assert(std::atomic<int>::is_always_lock_free, "shared between processes");

class SharedMarks {
 public:
  SharedMarks() {
    void* page = ::mmap(nullptr, sizeof(ChildMarks), PROT_READ | PROT_WRITE,
                        MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (page != MAP_FAILED) marks_ = new (page) ChildMarks();
  }
  ~SharedMarks() {
    if (marks_) ::munmap(marks_, sizeof(ChildMarks));
  }
  SharedMarks(const SharedMarks&) = delete;
  SharedMarks& operator=(const SharedMarks&) = delete;

  ChildMarks* get() const { return marks_; }  ///< null when the page could not be mapped

 private:
  ChildMarks* marks_ = nullptr;
};

// In the child only: where it marks a failed allocation.
ChildMarks* childMarks = nullptr;

void markFailedAllocation() {
  if (childMarks) childMarks->allocationFailed.store(1, std::memory_order_relaxed);
}

// operator new calls it when it finds no memory; then it throws std::bad_alloc as it would.
void onFailedNew() {
  markFailedAllocation();
  throw std::bad_alloc();
}

#if SOFTBAKE_ADDRESS_SANITIZER
// AddressSanitizer's allocator does not throw std::bad_alloc where it finds no memory: it reports
// and ends the process with status 1, as it does for a memory error. Its report tells the two
// apart.
void onSanitizerReport(const char* report) {
  if (std::strstr(report, "out of memory") || std::strstr(report, "allocation-size-too-big"))
    markFailedAllocation();
}
#endif

void watchAllocations(ChildMarks* marks) {
  childMarks = marks;
  std::set_new_handler(onFailedNew);
#if SOFTBAKE_ADDRESS_SANITIZER
  __asan_set_error_report_callback(onSanitizerReport);
#endif
}

// The address space this process maps now, in bytes; 0 when /proc does not say.
std::uint64_t mappedBytes() {
  const int fd = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  char text[128] = {};
  const ssize_t got = ::read(fd, text, sizeof text - 1);
  ::close(fd);
  if (got <= 0) return 0;
  const long pageSize = ::sysconf(_SC_PAGESIZE);
  return std::strtoull(text, nullptr, 10) * std::uint64_t(pageSize > 0 ? pageSize : 0);
}

// The child may map `bytes` more than it has: what it inherited (the parent's threads' stacks,
// a sanitizer's shadow memory reserved up front) is not the import's.
void capAddressSpace(std::uint64_t bytes) {
  if (bytes == 0) return;
  const std::uint64_t now = mappedBytes();
  if (now == 0) return;
  rlimit limit = {};
  if (::getrlimit(RLIMIT_AS, &limit) != 0) return;
  const rlim_t wanted = rlim_t(now + bytes);
  if (limit.rlim_cur != RLIM_INFINITY && limit.rlim_cur <= wanted) return;
  limit.rlim_cur = wanted;
  ::setrlimit(RLIMIT_AS, &limit);
}

// The tests' ways to an import past its limits (assimp_snapshot.hpp), before the reading.
void actAsTheTestsAsk() {
  if (const char* text = std::getenv("SOFTBAKE_TEST_IMPORT_STALL_SECONDS")) {
    const double seconds = std::strtod(text, nullptr);
    if (seconds > 0 && seconds < 1e6)
      std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  }
  if (const char* mebibytes = std::getenv("SOFTBAKE_TEST_IMPORT_ALLOCATE_MIB")) {
    constexpr std::size_t kBlock = std::size_t(64) << 20;
    std::vector<std::unique_ptr<char[]>> blocks;
    for (std::uint64_t left = std::strtoull(mebibytes, nullptr, 10) << 20; left > 0;
         left -= std::min<std::uint64_t>(left, kBlock)) {
      blocks.emplace_back(new char[kBlock]);
      blocks.back()[0] = 1;
    }
  }
}

// In the child: a crash is the parent's to report, the same way in every build. A sanitizer's or
// libFuzzer's handler would print a report, exit with status 1 instead of the signal, and
// libFuzzer's would also save the input as a finding of its own, though the parent goes on. Both
// refuse to let a program replace their handlers through sigaction(), so the kernel is asked
// directly; its struct sigaction differs from libc's.
void restoreDefaultCrashHandling() {
  for (const int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT}) {
#if defined(__linux__) && defined(__x86_64__)
    struct {
      void (*handler)(int);
      unsigned long flags;
      void (*restorer)();
      unsigned long mask;
    } action = {SIG_DFL, 0, nullptr, 0};
    ::syscall(SYS_rt_sigaction, signal, &action, nullptr, sizeof action.mask);
#else
    std::signal(signal, SIG_DFL);
#endif
  }
}

void closeQuietly(int fd) {
  while (::close(fd) < 0 && errno == EINTR) {
  }
}

}  // namespace

AssimpSnapshot takeAssimpSnapshot(const AssimpRead& read, unsigned postProcess) {
  AssimpSnapshot snapshot;
  const AssimpLogCapture log;
  Assimp::Importer importer;
  // Validation only, so the scene can be inspected as the loader made it before post-processing.
  const aiScene* scene = read(importer, aiProcess_ValidateDataStructure);
  if (scene) {
    snapshot.loaderVertices = vertexCount(*scene);
    snapshot.loaderFaces = faceCount(*scene);
    for (unsigned m = 0; m < scene->mNumMeshes; ++m)
      snapshot.loaderMeshVertices.push_back(scene->mMeshes[m]->mNumVertices);
    snapshot.unusedVertices = unusedVertices(*scene);
    snapshot.emptyFaces = dropEmptyFaces(*scene);
    matchPrimitiveTypesToFaces(*scene);
    scene = importer.ApplyPostProcessing(postProcess);
  }
  if (scene) {
    snapshot.meshes.reserve(scene->mNumMeshes);
    for (unsigned m = 0; m < scene->mNumMeshes; ++m)
      snapshot.meshes.push_back(copyMesh(*scene->mMeshes[m]));
    snapshot.nodes = copyNodes(scene->mRootNode);
  } else {
    snapshot.error = importer.GetErrorString();
    if (snapshot.error.empty()) snapshot.error = "unknown error";
  }
  snapshot.messages = log.messages();
  snapshot.unkeptMessages = log.unkept();
  return snapshot;
}

bool writeAssimpSnapshot(int fd, const AssimpSnapshot& snapshot) {
  Writer out(fd);
  out.number(kMagic);
  out.text(snapshot.error);
  out.number(snapshot.loaderVertices);
  out.number(snapshot.loaderFaces);
  out.values(snapshot.loaderMeshVertices);
  out.number(snapshot.unusedVertices);
  out.number(snapshot.emptyFaces);
  out.number(snapshot.meshes.size());
  for (const SnapshotMesh& mesh : snapshot.meshes) {
    out.text(mesh.name);
    out.values(mesh.positions);
    out.values(mesh.normals);
    out.values(mesh.uvs);
    out.values(mesh.triangles);
    out.number(mesh.points);
    out.number(mesh.lines);
  }
  out.number(snapshot.nodes.size());
  for (const SnapshotNode& node : snapshot.nodes) {
    out.text(node.name);
    out.bytes(node.transform.data(), sizeof(double) * 16);
    out.values(node.meshes);
    out.values(node.children);
  }
  out.number(snapshot.messages.size());
  for (const AssimpMessage& message : snapshot.messages) {
    out.number(message.severity == AssimpMessage::Severity::Error ? 1 : 0);
    out.text(message.text);
    out.number(message.repeats);
  }
  out.number(snapshot.unkeptMessages);
  out.number(kMagic);
  return out.flush();
}

namespace {

AssimpSnapshot readSnapshot(Reader& in) {
  if (in.number() != kMagic) throw std::runtime_error("the answer does not start as one");
  AssimpSnapshot snapshot;
  snapshot.error = in.text();
  snapshot.loaderVertices = in.number();
  snapshot.loaderFaces = in.number();
  snapshot.loaderMeshVertices = in.values<std::uint64_t>();
  snapshot.unusedVertices = in.number();
  snapshot.emptyFaces = in.number();
  for (std::uint64_t meshes = in.number(); meshes > 0; --meshes) {
    SnapshotMesh& mesh = snapshot.meshes.emplace_back();
    mesh.name = in.text();
    mesh.positions = in.values<Vec3f>();
    mesh.normals = in.values<Vec3f>();
    mesh.uvs = in.values<Vec2f>();
    mesh.triangles = in.values<Triangle>();
    mesh.points = in.number();
    mesh.lines = in.number();
  }
  for (std::uint64_t nodes = in.number(); nodes > 0; --nodes) {
    SnapshotNode& node = snapshot.nodes.emplace_back();
    node.name = in.text();
    in.bytes(node.transform.data(), sizeof(double) * 16);
    node.meshes = in.values<std::uint32_t>();
    node.children = in.values<std::uint32_t>();
  }
  for (std::uint64_t messages = in.number(); messages > 0; --messages) {
    AssimpMessage& message = snapshot.messages.emplace_back();
    message.severity =
        in.number() == 1 ? AssimpMessage::Severity::Error : AssimpMessage::Severity::Warning;
    message.text = in.text();
    message.repeats = std::size_t(in.number());
  }
  snapshot.unkeptMessages = std::size_t(in.number());
  if (in.number() != kMagic) throw std::runtime_error("the answer does not end as one");
  return snapshot;
}

}  // namespace

AssimpSnapshot readAssimpSnapshot(int fd) {
  Reader in(fd);
  return readSnapshot(in);
}

AssimpSnapshot takeAssimpSnapshotInChild(const AssimpRead& read, unsigned postProcess,
                                         const std::string& file, const ImportLimits& limits) {
  if constexpr (kThreadSanitizer) return takeAssimpSnapshot(read, postProcess);
  installAssimpLogging();
  const Clock::time_point deadline =
      Clock::now() + std::chrono::seconds(std::min(limits.maxSeconds, kMaxImportSeconds));
  const std::uint64_t memoryCap = importMemoryBytes(limits);
  const SharedMarks marks;
  int pipe[2];
  if (::pipe2(pipe, O_CLOEXEC) != 0)
    throw Error(
        cat(file, ": cannot start a process to read the file (", std::strerror(errno), ")"));
  const pid_t child = ::fork();
  if (child < 0) {
    const int why = errno;
    closeQuietly(pipe[0]);
    closeQuietly(pipe[1]);
    throw Error(cat(file, ": cannot start a process to read the file (", std::strerror(why), ")"));
  }
  if (child == 0) {
    closeQuietly(pipe[0]);
    // What a crash prints (a sanitizer's report, in checked builds) is assimp's business; the
    // parent says what happened, naming the file.
    const int devNull = ::open("/dev/null", O_WRONLY);
    if (devNull >= 0) ::dup2(devNull, STDERR_FILENO);
    restoreDefaultCrashHandling();
    watchAllocations(marks.get());
    capAddressSpace(memoryCap);
    AssimpSnapshot snapshot;
    try {
      actAsTheTestsAsk();
      snapshot = takeAssimpSnapshot(read, postProcess);
    } catch (const std::bad_alloc&) {
      markFailedAllocation();
      ::_exit(kOutOfMemoryStatus);
    } catch (const std::exception& e) {
      snapshot = AssimpSnapshot();
      snapshot.error = e.what();
    }
    // _exit: no atexit handlers, no flushing of stdio buffers the parent will flush itself.
    ::_exit(writeAssimpSnapshot(pipe[1], snapshot) ? 0 : 3);
  }
  closeQuietly(pipe[1]);

  AssimpSnapshot snapshot;
  std::string broken;
  bool outOfMemory = false, timedOut = false;
  try {
    Reader in(pipe[0], deadline);
    snapshot = readSnapshot(in);
  } catch (const AnswerTimedOut&) {
    timedOut = true;
    ::kill(child, SIGKILL);
  } catch (const std::bad_alloc&) {
    outOfMemory = true;
  } catch (const std::exception& e) {
    broken = e.what();
  }
  // Closed before waiting: a child still writing then stops (on a broken pipe) instead of
  // blocking on a pipe nobody reads.
  closeQuietly(pipe[0]);
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  if (timedOut) throw Error(importTimeLimitMessage(file, limits));
  if (outOfMemory) throw std::bad_alloc();
  const bool answered = WIFEXITED(status) && WEXITSTATUS(status) == 0 && broken.empty();
  // A failed allocation that assimp caught and turned into its error, or that ended the child.
  const bool allocationFailed =
      marks.get() && marks.get()->allocationFailed.load(std::memory_order_relaxed) != 0;
  if (allocationFailed && (!answered || !snapshot.error.empty()))
    throw Error(importMemoryLimitMessage(file, limits));
  if (WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
    throw Error(cat(file, ": the process reading the file was killed (", ::strsignal(SIGKILL),
                    "), most likely by the system for lack of memory: the import memory limit of ",
                    formatBytes(double(memoryCap)),
                    " is more than this machine could give it (--max-import-memory or "
                    "settings.import.max_memory_mib lowers it)"));
  if (WIFSIGNALED(status))
    throw Error(cat(file, ": assimp crashed reading the file (", ::strsignal(WTERMSIG(status)),
                    "): the file is corrupt, or trips a bug in assimp"));
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error(cat(file, ": assimp crashed reading the file (its process ended with status ",
                    WEXITSTATUS(status), "): the file is corrupt, or trips a bug in assimp"));
  if (!broken.empty())
    throw Error(
        cat(file, ": the process reading the file sent back a broken answer (", broken, ")"));
  return snapshot;
}

}  // namespace softbake
