#pragma once
// What the link tests share to run the independent MAVLink programs of test/mavlink_check
// (Node.js, node-mavlink): a node process started with an inherited descriptor as its fd 3, and
// the scratch directory its files go to (scratch_dir.hpp).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "scratch_dir.hpp"

namespace rgbdo {

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
