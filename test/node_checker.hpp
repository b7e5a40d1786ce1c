#pragma once
// What the link tests share to run the independent MAVLink programs of test/mavlink_check
// (Node.js, node-mavlink): a scratch directory per test, and a node process started with an
// inherited descriptor as its fd 3.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

namespace rgbdo {

// An empty directory under the system's temporary one, unique to this process, removed when
// the test that made it passed (kept, with the decoder's files, when it failed).
class ScratchDir {
 public:
  ScratchDir(const std::string& prefix, const std::string& name)
      : path_(std::filesystem::temp_directory_path() / (prefix + "_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    if (!::testing::Test::HasFailure()) std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Starts `node DIR/script args...`; `inherit_fd` (if >= 0) becomes its fd 3. Returns its pid.
inline pid_t start_node(const std::string& dir, const std::string& script, const std::vector<std::string>& args,
                        int inherit_fd) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (inherit_fd >= 0) ::dup2(inherit_fd, 3);
    std::vector<std::string> all{"node", dir + "/" + script};
    all.insert(all.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execvp("node", argv.data());
    ::_exit(127);
  }
  return pid;
}

}  // namespace rgbdo
