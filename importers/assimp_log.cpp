#include "importers/assimp_log.hpp"

#include <assimp/DefaultLogger.hpp>
#include <assimp/Logger.hpp>

#include <mutex>

#include "core/text.hpp"

namespace softbake {

namespace {

thread_local AssimpLogCapture* openCapture = nullptr;

// Debug and info messages narrate the import ("Found a matching importer…"); only warnings and
// errors can mean that something was left out.
class ForwardingLogger final : public Assimp::Logger {
 public:
  ForwardingLogger() : Assimp::Logger(Assimp::Logger::NORMAL) {}

  bool attachStream(Assimp::LogStream*, unsigned int) override { return false; }
  bool detachStream(Assimp::LogStream*, unsigned int) override { return false; }

 private:
  void OnDebug(const char*) override {}
  void OnVerboseDebug(const char*) override {}
  void OnInfo(const char*) override {}
  void OnWarn(const char* message) override { forward(AssimpMessage::Severity::Warning, message); }
  void OnError(const char* message) override { forward(AssimpMessage::Severity::Error, message); }

  static void forward(AssimpMessage::Severity severity, const char* message) {
    if (openCapture) openCapture->add(severity, message);
  }
};

}  // namespace

// Installed before the first capture opens and never replaced: DefaultLogger::set() deletes the
// logger it replaces, which another thread might be logging into at that moment.
void installAssimpLogging() {
  static std::once_flag installed;
  std::call_once(installed, [] { Assimp::DefaultLogger::set(new ForwardingLogger); });
}

AssimpLogCapture::AssimpLogCapture() : outer_(openCapture) {
  installAssimpLogging();
  openCapture = this;
}

AssimpLogCapture::~AssimpLogCapture() {
  openCapture = outer_;
}

void AssimpLogCapture::add(AssimpMessage::Severity severity, const char* text) {
  std::string message = text ? text : "";
  while (!message.empty() && static_cast<unsigned char>(message.back()) <= ' ') message.pop_back();
  std::string key = (severity == AssimpMessage::Severity::Error ? "E" : "W") + message;
  if (const auto same = index_.find(key); same != index_.end()) {
    ++messages_[same->second].repeats;
  } else if (messages_.size() < kMaxKept) {
    index_.emplace(std::move(key), messages_.size());
    messages_.push_back({severity, std::move(message)});
  } else {
    ++unkept_;
  }
}

std::vector<std::string> describeAssimpMessages(const std::string& file,
                                                const std::vector<AssimpMessage>& messages,
                                                std::size_t unkept, std::size_t maxLines) {
  std::vector<std::string> lines;
  for (std::size_t i = 0; i < messages.size() && i < maxLines; ++i) {
    const AssimpMessage& message = messages[i];
    lines.push_back(
        cat(file, ": assimp", message.severity == AssimpMessage::Severity::Error ? " error" : "",
            ": ", message.text, message.repeats > 1 ? cat(" (", message.repeats, " times)") : ""));
  }
  const std::size_t more = messages.size() - lines.size() + unkept;
  if (more > 0) lines.push_back(cat(file, ": assimp: ", more, " more messages"));
  return lines;
}

}  // namespace softbake
