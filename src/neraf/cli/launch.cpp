// `neraf launch -n N -- train ...`: data-parallel training with N local processes of this same
// program (train/distributed.h), as torchrun does for one machine: each child gets
// --world-size N --rank i --master 127.0.0.1:PORT. Rank 0 writes to this terminal as usual; the
// other ranks run --quiet and their lines are prefixed "[rank i] ". Ctrl-C / SIGTERM is
// forwarded once to every child (each stops after the same step; rank 0 saves a checkpoint). If
// a child fails, the others are stopped (SIGTERM, then SIGKILL after --grace seconds) and launch
// exits with the failed child's code.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "neraf/cli/commands.h"
#include "neraf/cli/flag_checks.h"
#include "neraf/cli/system_info.h"
#include "neraf/infer/train_config.h"
#include "neraf/train/interrupt.h"
#include "neraf/util/error.h"

namespace neraf::cli {

namespace {

struct LaunchArgs {
  int nproc = 2;
  int master_port = 0;
  double grace = 60;
  std::vector<std::string> command;
};

// A TCP port that is free on 127.0.0.1 now (the kernel's pick).
int free_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  require(fd >= 0, std::string("launch: cannot open a socket (") + std::strerror(errno) + ")");
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
                  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0;
  ::close(fd);
  require(ok, std::string("launch: cannot find a free port (") + std::strerror(errno) +
                  "); pass --master-port");
  return ntohs(a.sin_port);
}

struct Child {
  int rank = 0;
  pid_t pid = -1;
  int out = -1;         // read end of the child's stdout+stderr (ranks > 0), else -1
  std::string pending;  // a partial line not yet printed
  bool running = true;
  int code = 0;  // exit code (128 + signal when killed)
};

void print_prefixed(Child& c, const char* data, size_t n, bool flush_all) {
  c.pending.append(data, n);
  size_t start = 0;
  for (size_t nl; (nl = c.pending.find('\n', start)) != std::string::npos; start = nl + 1)
    std::fprintf(stderr, "[rank %d] %.*s\n", c.rank, static_cast<int>(nl - start),
                 c.pending.data() + start);
  c.pending.erase(0, start);
  if (flush_all && !c.pending.empty()) {
    std::fprintf(stderr, "[rank %d] %s\n", c.rank, c.pending.c_str());
    c.pending.clear();
  }
}

pid_t spawn(const std::vector<std::string>& argv, int out_fd) {
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  std::string exe = own_executable();
  if (exe.empty()) exe = "/proc/self/exe";
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  require(pid >= 0, std::string("launch: cannot start a process (") + std::strerror(errno) + ")");
  if (pid == 0) {
    // Own process group: a terminal's Ctrl-C reaches launch only, which forwards it once (a
    // second SIGINT would end a child without its checkpoint). A child of a killed launch gets
    // SIGTERM.
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(1);
    if (out_fd >= 0) {
      ::dup2(out_fd, STDOUT_FILENO);
      ::dup2(out_fd, STDERR_FILENO);
      ::close(out_fd);
    }
    ::execv(exe.c_str(), cargv.data());
    std::fprintf(stderr, "error: launch: cannot run %s (%s)\n", exe.c_str(), std::strerror(errno));
    ::_exit(127);
  }
  return pid;
}

// The value of `name` in a train command line ("--name V" or "--name=V"); "" when absent.
std::string flag_value(const std::vector<std::string>& command, const std::string& name) {
  for (size_t i = 0; i < command.size(); ++i) {
    if (command[i] == name && i + 1 < command.size()) return command[i + 1];
    if (command[i].rfind(name + "=", 0) == 0) return command[i].substr(name.size() + 1);
  }
  return "";
}

// Before any process starts: every rank trains an equal share of the global batches, so N must
// divide the rays per batch and the acoustic batch of the config train will use. A command
// train would refuse for another reason passes here (train then says why).
void check_batches_split(const std::vector<std::string>& command, int n) {
  infer::TrainConfig cfg;
  try {
    if (std::find(command.begin(), command.end(), "--resume") != command.end()) {
      cfg = infer::read_run_config(flag_value(command, "--out") + "/config.json");
    } else {
      infer::TrainFlags flags;
      const std::string preset = flag_value(command, "--preset"),
                        rays = flag_value(command, "--rays");
      const std::string modality = flag_value(command, "--modality");
      if (!preset.empty()) flags.preset = preset;
      if (!modality.empty()) flags.modality = infer::parse_modality(modality);
      if (!rays.empty()) flags.rays = std::stoll(rays);
      cfg = infer::resolve_train_config(flags);
    }
  } catch (const std::exception&) {
    return;
  }
  auto splits = [](int64_t batch) {
    std::string list;
    for (int d = 2; d <= 64; ++d)
      if (batch % d == 0) list += (list.empty() ? "" : ", ") + std::to_string(d);
    return list;
  };
  const std::string N = std::to_string(n);
  if (cfg.modality != infer::Modality::audio && cfg.rays_per_batch % n != 0)
    throw Error("launch -n " + N + ": the batch of " + std::to_string(cfg.rays_per_batch) +
                " rays (--rays) does not split evenly over " + N + " processes; use -n " +
                splits(cfg.rays_per_batch) + " (if any), or a --rays that " + N + " divides");
  if (cfg.modality != infer::Modality::vision && cfg.audio.batch_size % n != 0)
    throw Error("launch -n " + N + ": the acoustic batch of " +
                std::to_string(cfg.audio.batch_size) + " slices (preset " + cfg.preset +
                ") does not split evenly over " + N + " processes; use -n " +
                splits(cfg.audio.batch_size));
}

int run_launch(const LaunchArgs& args) {
  require(!args.command.empty() && args.command[0] == "train",
          "launch: expected '-- train ...' after launch's own flags (e.g. neraf launch -n 2 -- "
          "train --data DATA --out RUN)");
  for (const auto& a : args.command)
    for (const char* own : {"--world-size", "--rank", "--master"})
      require(a != own && a.rfind(std::string(own) + "=", 0) != 0,
              std::string("launch: ") + own +
                  " is set by launch for each process; remove it (use -n and --master-port)");
  const int port = args.master_port > 0 ? args.master_port : free_port();
  bool quiet_given = false;
  for (const auto& a : args.command) quiet_given |= a == "--quiet";
  // Threads per process: the given --threads (checked by train), else the cores shared out, as
  // torchrun does; more threads than cores in all makes every rank wait on the others.
  const int cores = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::string> command = args.command;
  int threads = std::atoi(flag_value(command, "--threads").c_str());
  if (threads == 0) {
    threads = std::max(1, cores / args.nproc);
    command.insert(command.end(), {"--threads", std::to_string(threads)});
  }
  if (args.nproc * threads > cores) {
    const std::string advice = args.nproc > cores
                                   ? "use -n " + std::to_string(cores) + " or fewer"
                                   : "give each --threads " + std::to_string(cores / args.nproc);
    std::fprintf(stderr,
                 "warning: launch: %d processes x %d threads = %d threads on %d cores; the ranks "
                 "will wait on each other (%s)\n",
                 args.nproc, threads, args.nproc * threads, cores, advice.c_str());
  }

  check_batches_split(args.command, args.nproc);
  train::InterruptGuard interrupt;  // Ctrl-C / SIGTERM → forwarded to the children
  std::vector<Child> children(static_cast<size_t>(args.nproc));
  for (int r = 0; r < args.nproc; ++r) {
    Child& c = children[static_cast<size_t>(r)];
    c.rank = r;
    std::vector<std::string> argv = {"neraf"};
    argv.insert(argv.end(), command.begin(), command.end());
    argv.insert(argv.end(), {"--world-size", std::to_string(args.nproc), "--rank",
                             std::to_string(r), "--master", "127.0.0.1:" + std::to_string(port)});
    int pipe_fds[2] = {-1, -1};
    if (r > 0) {
      if (!quiet_given) argv.push_back("--quiet");
      require(::pipe2(pipe_fds, O_CLOEXEC) == 0,
              std::string("launch: cannot make a pipe (") + std::strerror(errno) + ")");
    }
    c.pid = spawn(argv, pipe_fds[1]);
    if (r > 0) {
      ::close(pipe_fds[1]);
      c.out = pipe_fds[0];
    }
  }

  using Clock = std::chrono::steady_clock;
  bool forwarded = false;
  int failed_rank = -1;
  Clock::time_point kill_at{};
  for (;;) {
    // Children's output.
    std::vector<pollfd> fds;
    std::vector<Child*> owners;
    for (auto& c : children)
      if (c.out >= 0) {
        fds.push_back({c.out, POLLIN, 0});
        owners.push_back(&c);
      }
    ::poll(fds.data(), fds.size(), 100);
    for (size_t i = 0; i < fds.size(); ++i) {
      if (!(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      char buf[4096];
      const ssize_t n = ::read(fds[i].fd, buf, sizeof buf);
      if (n > 0) {
        print_prefixed(*owners[i], buf, static_cast<size_t>(n), false);
      } else if (n == 0 || (errno != EINTR && errno != EAGAIN)) {
        print_prefixed(*owners[i], "", 0, true);
        ::close(owners[i]->out);
        owners[i]->out = -1;
      }
    }
    // Exits.
    for (auto& c : children) {
      if (!c.running) continue;
      int status = 0;
      if (::waitpid(c.pid, &status, WNOHANG) != c.pid) continue;
      c.running = false;
      c.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      if (c.code != 0 && failed_rank < 0) {
        failed_rank = c.rank;
        std::fprintf(stderr, "launch: rank %d exited with code %d; stopping the other ranks\n",
                     c.rank, c.code);
        for (auto& o : children)
          if (o.running) ::kill(o.pid, SIGTERM);
        kill_at = Clock::now() + std::chrono::milliseconds(static_cast<int64_t>(args.grace * 1e3));
      }
    }
    if (interrupt.requested() && !forwarded) {
      forwarded = true;
      for (auto& c : children)
        if (c.running) ::kill(c.pid, SIGINT);
    }
    if (failed_rank >= 0 && Clock::now() >= kill_at)
      for (auto& c : children)
        if (c.running) ::kill(c.pid, SIGKILL);
    bool busy = false;
    for (const auto& c : children) busy |= c.running || c.out >= 0;
    if (!busy) break;
  }
  if (failed_rank >= 0) return children[static_cast<size_t>(failed_rank)].code;
  for (const auto& c : children)
    if (c.code != 0) return c.code;
  return 0;
}

}  // namespace

void register_launch(CLI::App& app) {
  auto args = std::make_shared<LaunchArgs>();
  CLI::App* cmd = app.add_subcommand(
      "launch", "Train with several local processes (data-parallel, PyTorch c10d / Gloo)");
  cmd->footer(
      "Starts N processes of `neraf train ARGS --world-size N --rank i --master 127.0.0.1:PORT`\n"
      "on this machine. Every process draws the same global batch and trains on its own share;\n"
      "the gradients are averaged (all-reduce), so N processes train what one would, with the\n"
      "same --rays. Rank 0 writes the run folder and the progress bar; the other ranks' lines\n"
      "are prefixed [rank i]. Each process gets --threads T (default: the cores / N; N x T above\n"
      "the cores is warned about). Ctrl-C stops every rank after the same step with a\n"
      "checkpoint; if one rank fails the others are stopped and launch exits non-zero. For\n"
      "several machines run `neraf train` with those flags on each (README, \"Several\n"
      "processes or machines\").\n"
      "Example: neraf launch -n 2 -- train --data demo/ --out runs/demo");
  cmd->add_option("-n,--nproc", args->nproc,
                  "Number of processes (ranks), 2 or more (one process: run neraf train)")
      ->transform(whole_number(2, 64))
      ->required();
  cmd->add_option("--master-port", args->master_port,
                  "TCP port of rank 0 on 127.0.0.1 (default: a free port)")
      ->transform(whole_number(1, 65535));
  cmd->add_option("--grace", args->grace,
                  "Seconds the other ranks get to stop after one failed, before SIGKILL")
      ->check(real_number(0, 86400))
      ->capture_default_str();
  cmd->add_option("command", args->command, "After --: train and its flags")->required();
  cmd->allow_extras();  // train's flags without "--" before them: said below, not a CLI11 list
  cmd->callback([args, cmd]() {
    if (cmd->remaining_size() > 0)  // the "--" mark itself is not counted
      throw CLI::ValidationError(
          "launch: put -- between launch's flags and the train command "
          "(neraf launch -n 2 -- train --data DATA --out RUN); without it "
          "train's flags are read as launch's");
    const int code = run_launch(*args);
    if (code != 0) throw ExitCode{code};
  });
}

}  // namespace neraf::cli
