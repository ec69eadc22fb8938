#include "app/session.h"

namespace triadcal {

void Session::RecordInput(const std::string& role, const std::string& path) {
  provenance.RecordInput(role, path);
  NoteInput(path);
}

void Session::RecordInput(const std::string& role, const std::string& path,
                          const std::string& sha256) {
  provenance.RecordInput(role, path, sha256);
  NoteInput(path);
}

void Session::NoteInput(const std::string& path) const {
  if (output_guard) output_guard->NoteInput(path);
}

void Session::NoteOutput(const std::string& path) const {
  if (output_guard) output_guard->NoteOutput(path);
}

}  // namespace triadcal
