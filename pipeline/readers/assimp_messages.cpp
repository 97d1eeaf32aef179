#include "pipeline/readers/assimp_messages.h"

#include <assimp/DefaultLogger.hpp>
#include <assimp/LogStream.hpp>
#include <algorithm>
#include <mutex>

namespace cellbake {
namespace {

// One capture at a time: assimp has a single logger per process.
std::mutex& capture_mutex() {
  static std::mutex m;
  return m;
}

// "Warn,  T0: text\n" -> (" assimp warning: ", "text").
std::string as_warning(std::string message) {
  while (!message.empty() && (message.back() == '\n' || message.back() == '\r')) message.pop_back();
  const bool error = message.rfind("Error", 0) == 0;
  const std::size_t colon = message.find(": ");
  std::string text = colon == std::string::npos ? message : message.substr(colon + 2);
  text.erase(0, text.find_first_not_of(' '));
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return std::string(error ? " assimp error: " : " assimp warning: ") + text;
}

}  // namespace

struct AssimpMessages::Capture : Assimp::LogStream {
  std::unique_lock<std::mutex> lock{capture_mutex()};
  std::vector<std::string> messages;  // distinct, in order
  std::size_t repeated = 0;
  void write(const char* message) override {
    std::string w = as_warning(message ? message : "");
    if (std::find(messages.begin(), messages.end(), w) == messages.end())
      messages.push_back(std::move(w));
    else
      ++repeated;
  }
};

AssimpMessages::AssimpMessages() : capture_(std::make_unique<Capture>()) {
  Assimp::DefaultLogger::create(nullptr, Assimp::Logger::NORMAL, 0);
  Assimp::DefaultLogger::get()->attachStream(capture_.get(), Assimp::Logger::Warn | Assimp::Logger::Err);
}

AssimpMessages::~AssimpMessages() {
  // Detached first: the logger deletes the streams still attached when killed.
  Assimp::DefaultLogger::get()->detachStream(capture_.get(), Assimp::Logger::Warn | Assimp::Logger::Err);
  Assimp::DefaultLogger::kill();
}

std::vector<std::string> AssimpMessages::warnings(std::size_t max_messages) const {
  const std::vector<std::string>& all = capture_->messages;
  std::vector<std::string> out(all.begin(), all.begin() + std::ptrdiff_t(std::min(max_messages, all.size())));
  if (all.size() > max_messages)
    out.push_back(" assimp: " + std::to_string(all.size() - max_messages) + " more distinct messages");
  return out;
}

}  // namespace cellbake
