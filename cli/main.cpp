#include <unistd.h>

#include <iostream>

#include "commands.hpp"

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  return pdyn::cli::run_command(args, std::cout, std::cerr, ::isatty(STDERR_FILENO) != 0);
}
