// Errors that carry their location: the file, the field inside it (a JSON path such as
// `objects[2].material.roughness`, a setting key, an EXR channel) and what was expected.
// Every bad-input path in freqlab throws this; the CLI prints what() and exits non-zero,
// the UI shows it in a panel, tests assert on file() / field().
#pragma once

#include <stdexcept>
#include <string>

namespace freqlab {

class Error : public std::runtime_error {
  public:
    Error(std::string file, std::string field, const std::string& message)
        : std::runtime_error(format(file, field, message)),
          file_(std::move(file)),
          field_(std::move(field)),
          message_(message) {}

    const std::string& file() const { return file_; }
    const std::string& field() const { return field_; }
    const std::string& message() const { return message_; }

  private:
    static std::string format(const std::string& file, const std::string& field,
                              const std::string& message) {
        std::string s;
        if (!file.empty()) s += file + ": ";
        if (!field.empty()) s += field + ": ";
        return s + message;
    }
    std::string file_, field_, message_;
};

// Thrown by a job whose cancel flag was raised; not an error the user must fix.
class Cancelled : public std::runtime_error {
  public:
    Cancelled() : std::runtime_error("cancelled") {}
};

}  // namespace freqlab
