// Cancel-at-random (issue "Reliability", acceptance 4): `freqlab render`, `bake` and `bench`
// are started over the complete output of an earlier run and sent SIGINT (what Ctrl-C sends)
// after a random delay spread over their whole run time; 50 times in all. After each, the
// output directory must hold no temporary file, keep every earlier file, and every file in it
// must be either byte-identical to the earlier one or complete (EXR and PNG decode, JSON
// parses). Exit status: 0 (finished first) or 130 (cancelled); anything else fails.
//
// Usage: freqlab_cancel_test FREQLAB SOURCE_DIR WORK_DIR [RUNS] [SEED]
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "base/file_io.h"
#include "image/image_io.h"

namespace fs = std::filesystem;
using namespace freqlab;

namespace {

struct Command {
    std::string name;
    std::vector<std::string> args;  // after the binary, before --out DIR
};

// Runs freqlab with `args` + --out `out`; sends SIGINT after `delay_s` (< 0: never). Returns
// the exit status (128 + signal when killed by one).
int run(const std::string& freqlab, const std::vector<std::string>& args, const fs::path& out,
        double delay_s) {
    std::vector<std::string> all = {freqlab};
    all.insert(all.end(), args.begin(), args.end());
    all.push_back("--out");
    all.push_back(out.string());
    const pid_t pid = fork();
    if (pid == 0) {
        std::vector<char*> argv;
        for (std::string& a : all) argv.push_back(a.data());
        argv.push_back(nullptr);
        if (!freopen("/dev/null", "w", stdout) || !freopen("/dev/null", "w", stderr)) _exit(126);
        execv(argv[0], argv.data());
        _exit(127);
    }
    int status = 0;
    if (delay_s >= 0) {
        // A run that ends before its delay is not waited out (a cold table cache made the
        // delays of bakes 40 s long and the test 14 minutes).
        const auto until =
            std::chrono::steady_clock::now() + std::chrono::duration<double>(delay_s);
        while (std::chrono::steady_clock::now() < until) {
            if (waitpid(pid, &status, WNOHANG) == pid)
                return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        kill(pid, SIGINT);
    }
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::map<std::string, std::string> snapshot(const fs::path& dir) {
    std::map<std::string, std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(dir))
        if (e.is_regular_file())
            files[fs::relative(e.path(), dir).string()] = read_text_file(e.path());
    return files;
}

// Empty when `path` is a complete file of its kind, else why not.
std::string check_complete(const fs::path& path) {
    const std::string ext = path.extension().string();
    try {
        if (ext == ".exr") {
            read_exr(path);
        } else if (ext == ".png") {
            read_rgb_image(path, false);
        } else if (ext == ".json") {
            if (nlohmann::json::parse(read_text_file(path)).is_discarded())
                return "JSON that does not parse";
        } else if (ext == ".csv") {
            const std::string text = read_text_file(path);
            if (text.empty() || text.back() != '\n') return "a CSV file not ending in a newline";
        }
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

// Copies `from` over a fresh `to`.
void reset_dir(const fs::path& from, const fs::path& to) {
    fs::remove_all(to);
    fs::create_directories(to);
    fs::copy(from, to, fs::copy_options::recursive);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s FREQLAB SOURCE_DIR WORK_DIR [RUNS] [SEED]\n", argv[0]);
        return 2;
    }
    const std::string freqlab = argv[1];
    const fs::path src = argv[2], work = argv[3];
    const int runs = argc > 4 ? std::atoi(argv[4]) : 50;
    const unsigned seed = argc > 5 ? unsigned(std::atoi(argv[5])) : 2026u;
    const std::string scenes = (src / "scenes").string();
    const std::vector<Command> commands = {
        {"render",
         {"render", scenes + "/rotor.json", "--method", "cache", "--frames", "0:8", "--size",
          "96x54", "--quiet"}},
        {"bake",
         {"bake", scenes + "/cornell_fog.json", "--method", "impulse", "--spp", "16", "--set",
          "bake.max_size=64", "--quiet"}},
        {"bench",
         {"bench", scenes + "/rotor.json", "--study", "sparse", "--size", "64x36", "--runs", "2"}},
    };
    fs::remove_all(work);
    // The earlier runs: complete outputs, timed (the delays spread over 1.2 x that time).
    std::vector<double> seconds;
    for (const Command& c : commands) {
        // Once untimed: what a first run builds and caches (the impulse tables) is not what
        // the cancelled runs do.
        run(freqlab, c.args, work / ("warm_" + c.name), -1);
        const auto t0 = std::chrono::steady_clock::now();
        const int rc = run(freqlab, c.args, work / ("earlier_" + c.name), -1);
        seconds.push_back(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        if (rc != 0) {
            std::fprintf(stderr, "FAIL: the uncancelled %s exited with %d\n", c.name.c_str(), rc);
            return 1;
        }
    }
    std::mt19937 rng(seed);
    int failures = 0, cancelled = 0, finished = 0;
    for (int i = 0; i < runs; ++i) {
        const size_t which = size_t(i) % commands.size();
        const Command& c = commands[which];
        const fs::path earlier = work / ("earlier_" + c.name), out = work / "out";
        reset_dir(earlier, out);
        const auto before = snapshot(out);
        const double delay = std::uniform_real_distribution<double>(0.0, 1.2)(rng) * seconds[which];
        const int rc = run(freqlab, c.args, out, delay);
        auto fail = [&](const std::string& why) {
            ++failures;
            std::fprintf(stderr, "FAIL run %d (%s, SIGINT after %.3f s, exit %d): %s\n", i,
                         c.name.c_str(), delay, rc, why.c_str());
        };
        if (rc == 130)
            ++cancelled;
        else if (rc == 0)
            ++finished;
        else
            fail("exit status neither 0 nor 130");
        const auto after = snapshot(out);
        for (const auto& [name, bytes] : before)
            if (!after.count(name)) fail("the earlier " + name + " is gone");
        for (const auto& [name, bytes] : after) {
            if (fs::path(name).filename().string().rfind('.', 0) == 0)
                fail("a temporary file is left: " + name);
            auto it = before.find(name);
            if (it != before.end() && it->second == bytes) continue;
            const std::string why = check_complete(out / name);
            if (!why.empty()) fail(name + " is not complete: " + why);
        }
    }
    std::printf(
        "cancel at random: %d runs (%d cancelled, %d finished first), %d failures; "
        "full run times render %.2f s, bake %.2f s, bench %.2f s, seed %u\n",
        runs, cancelled, finished, failures, seconds[0], seconds[1], seconds[2], seed);
    return failures == 0 ? 0 : 1;
}
