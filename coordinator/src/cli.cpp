#include "sphfsi/coordinator/cli.hpp"

#include <iostream>

#include "sphfsi/coordinator/git_revision.hpp"
#include "sphfsi/coordinator/run.hpp"
#include "sphfsi/coordinator/scene.hpp"
#include "sphfsi/coordinator/scene_warnings.hpp"
#include "sphfsi/coordinator/version.hpp"
#include "sphfsi/protocol/message.hpp"

namespace sphfsi::coordinator {
namespace {
const char* kUsage =
    "usage:\n"
    "  sphfsi run SCENE.toml --out DIR [--overwrite] [--set key.path=value ...] [--listen ENDPOINT] [--quiet]\n"
    "  sphfsi run --resume DIR [--quiet]\n"
    "  sphfsi check SCENE.toml [--set key.path=value ...]\n"
    "  sphfsi schema            print every scene key as markdown (docs/scenes.md)\n"
    "  sphfsi version\n"
    "\n"
    "run starts the participants the scene needs on 127.0.0.1 and records into DIR/record.h5;\n"
    "a DIR that already holds a record is refused unless --overwrite is given.\n"
    "--listen tcp://ADDRESS:PORT binds there instead and waits for participants started elsewhere\n"
    "(a non-loopback address exposes the run to that network: an explicit choice).\n";

int usage_error(const std::string& why) {
    std::cerr << "sphfsi: " << why << "\n" << kUsage;
    return 2;
}
}  // namespace

int main_cli(int argc, char** argv) {
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
        std::cout << kUsage;
        return args.empty() ? 2 : 0;
    }
    const std::string command = args[0];
    RunOptions opt;
    std::string scene;
    bool out_given = false;
    for (std::size_t i = 1; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto value = [&]() -> const std::string* { return i + 1 < args.size() ? &args[++i] : nullptr; };
        if (a == "--set") {
            auto v = value();
            if (!v) return usage_error("--set needs key.path=value");
            opt.overrides.push_back(*v);
        } else if (a == "--out") {
            auto v = value();
            if (!v) return usage_error("--out needs a directory");
            opt.out_dir = *v;
            out_given = true;
        } else if (a == "--listen") {
            auto v = value();
            if (!v) return usage_error("--listen needs an endpoint such as tcp://127.0.0.1:5555");
            opt.listen = *v;
        } else if (a == "--resume") {
            auto v = value();
            if (!v) return usage_error("--resume needs the output directory of the run");
            if (opt.resume) return usage_error("--resume is given twice");
            opt.resume = true;
            opt.out_dir = *v;
        } else if (a == "--overwrite") {
            opt.overwrite = true;
        } else if (a == "--quiet") {
            opt.quiet = true;
        } else if (!a.empty() && a[0] == '-') {
            return usage_error("unknown option " + a);
        } else if (scene.empty()) {
            scene = a;
        } else {
            return usage_error("unexpected argument " + a);
        }
    }
    if (command == "version") {
        std::cout << "sphfsi " << kSoftwareVersion << " (git " << kGitRevision << ", protocol "
                  << protocol::kProtocolVersion << ")\n";
        return 0;
    }
    if (command == "schema") {
        std::cout << scene_reference();
        return 0;
    }
    if (command == "check") {
        if (scene.empty()) return usage_error("check needs a scene file");
        try {
            Scene s = load_scene(scene, opt.overrides);
            const std::string roles = s.has("structure") && s.has("fluid") ? "structure fluid" : s.has("fluid") ? "fluid" : "structure";
            std::cout << scene << ": valid; participants: " << roles << "\n";
            for (const std::string& w : scene_warnings(s)) std::cerr << "sphfsi: warning: " << w << "\n";
            return 0;
        } catch (const ConfigError& e) {
            std::cerr << "sphfsi: invalid scene:\n" << e.what() << "\n";
            return 2;
        }
    }
    if (command == "run") {
        if (!opt.resume && scene.empty()) return usage_error("run needs a scene file (or --resume DIR)");
        if (opt.resume && !scene.empty()) return usage_error("--resume takes the scene from the checkpoint; give no scene");
        // A resumed run must continue the interrupted one exactly, in its own directory.
        if (opt.resume && !opt.overrides.empty())
            return usage_error("--resume continues the run as it was; --set cannot change it (start a new run instead)");
        if (opt.resume && out_given) return usage_error("--resume DIR resumes in DIR; give no --out");
        if (opt.resume && opt.overwrite) return usage_error("--resume continues the record in DIR; --overwrite would discard it");
        if (opt.out_dir.empty()) return usage_error("run needs --out DIR");
        opt.scene = scene;
        return run_scene(opt);
    }
    return usage_error("unknown command " + command);
}

}  // namespace sphfsi::coordinator
