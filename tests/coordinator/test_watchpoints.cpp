// watchpoints.csv on a resume (coordinator/src/watchpoints.cpp): the rows up to the checkpoint go to
// watchpoints.csv.resuming, which replaces watchpoints.csv only once the run has passed the file's last row.
// The file's rows run ahead of the record's (the record is flushed at frames, the rows whenever the stream's
// buffer fills): a resume taking over when the record caught up, then interrupted, had cut rows the
// interrupted run had written (a review, 2026-11-27).
#include <doctest/doctest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "sphfsi/coordinator/watchpoints.hpp"

using namespace sphfsi;
using namespace sphfsi::coordinator;

namespace {

std::string read_text(const std::filesystem::path& file) {
    std::ifstream in(file);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// One watchpoint on a one-cell interface, and a file the interrupted run left: rows to t = 0.7 s, checkpoint
// at 0.5 s, the last row cut short by the kill.
struct Interrupted {
    std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                ("sphfsi_test_watchpoints_" + std::to_string(::getpid()));
    std::filesystem::path file = dir / "watchpoints.csv";
    Value scene{Value::Table{{"watchpoint", Value(Value::Array{Value(Value::Table{
                                                  {"name", Value(std::string("tip"))}, {"x", Value(1.0)}, {"y", Value(1.0)}})})}}};
    protocol::InterfaceMesh mesh{protocol::F64Array({4, 2}, {0, 0, 1, 0, 1, 1, 0, 1}), protocol::I32Array({1, 4}, {0, 1, 2, 3})};
    std::string before = "time,name,x,y,dx,dy\n0.5,tip,1,1,0,0\n0.6,tip,1,1,0,0\n0.7,tip,1,1,0,0\n0.";
    Interrupted() {
        std::filesystem::create_directories(dir);
        std::ofstream(file) << before;
    }
    ~Interrupted() { std::filesystem::remove_all(dir); }
};

}  // namespace

TEST_SUITE("watchpoints") {
    TEST_CASE("a resume stopped before the file's last row leaves watchpoints.csv as it was") {
        Interrupted run;
        Watchpoints w(run.file, run.scene, run.mesh, true, 0.5);
        CHECK(w.resume_pending());
        CHECK(w.history_end() == 0.7);
        w.write(0.6, protocol::F64Array::zeros(4, 2));
        w.take_over_when_caught_up(0.65);  // past the record's end (0.5), not the file's
        CHECK(w.resume_pending());
        w.flush();
        w.abandon_resume();
        CHECK(read_text(run.file) == run.before);
        CHECK(!std::filesystem::exists(run.dir / "watchpoints.csv.resuming"));
    }

    TEST_CASE("a resume that passes the file's last row replaces it with the rows to the checkpoint and its own") {
        Interrupted run;
        Watchpoints w(run.file, run.scene, run.mesh, true, 0.5);
        for (double t : {0.6, 0.7}) {
            w.write(t, protocol::F64Array::zeros(4, 2));
            w.take_over_when_caught_up(t);
        }
        CHECK(!w.resume_pending());
        w.write(0.8, protocol::F64Array::zeros(4, 2));
        w.flush();
        CHECK(read_text(run.file) == "time,name,x,y,dx,dy\n0.5,tip,1,1,0,0\n0.6,tip,1,1,0,0\n0.7,tip,1,1,0,0\n"
                                     "0.8,tip,1,1,0,0\n");
    }
}
