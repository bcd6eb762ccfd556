#pragma once
/// What assimp logs while it reads one file, caught so that the warnings it would otherwise only
/// log (a dropped face, an ignored attribute) reach the user, attributed to the file.
///
/// assimp has one logger for the whole process (Assimp::DefaultLogger). softbake installs its own
/// once and never replaces it; it hands each message to the capture open on the calling thread, so
/// imports on different threads keep their messages apart and none blocks another.

#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

namespace softbake {

struct AssimpMessage {
  enum class Severity { Warning, Error };
  Severity severity = Severity::Warning;
  std::string text;
  std::size_t repeats = 1;  ///< identical messages are kept once and counted
};

/// Collects assimp's warnings and errors on this thread from construction to destruction. Captures
/// nest: an inner one takes the messages while it is open.
class AssimpLogCapture {
 public:
  AssimpLogCapture();
  ~AssimpLogCapture();
  AssimpLogCapture(const AssimpLogCapture&) = delete;
  AssimpLogCapture& operator=(const AssimpLogCapture&) = delete;

  /// In the order first seen; at most kMaxKept different ones.
  const std::vector<AssimpMessage>& messages() const { return messages_; }
  /// Messages past the first kMaxKept different ones, counted but not kept.
  std::size_t unkept() const { return unkept_; }

  void add(AssimpMessage::Severity severity, const char* text);

  /// A corrupt file can make a loader log a different message per face.
  static constexpr std::size_t kMaxKept = 1000;

 private:
  std::vector<AssimpMessage> messages_;
  std::unordered_map<std::string, std::size_t> index_;  // severity letter + text -> messages_
  std::size_t unkept_ = 0;
  AssimpLogCapture* outer_;
};

/// Installs softbake's logger into assimp, once per process; AssimpLogCapture does it too. A
/// process that forks to read a file calls it first, so the child never runs the one-time set-up
/// (and its lock) that another thread of the parent might have been inside when it forked.
void installAssimpLogging();

/// "a.fbx: assimp: FBX-DOM: unsupported, newer format version, … (3 times)": one line per
/// message, at most `maxLines`, then one that says how many more there were (`unkept` of them
/// beyond those in the list).
std::vector<std::string> describeAssimpMessages(const std::string& file,
                                                const std::vector<AssimpMessage>& messages,
                                                std::size_t unkept, std::size_t maxLines = 10);

}  // namespace softbake
