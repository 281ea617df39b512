// The XDMF sidecar (Recorder::write_xdmf) for fields a foreign participant may send: it describes the fluid's
// frames alone, and only what XDMF can say. A review (2026-11-27) found a 3-component position declared as 2
// and a field of more axes given dimensions its dataset does not have (ParaView's read fails), and a foreign
// structure's frames replacing the fluid's sidecar.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>  // getpid

#include "sphfsi/coordinator/recorder.hpp"

namespace {
using sphfsi::protocol::F64Array;
using sphfsi::protocol::Fields;

std::string read_text(const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}
}  // namespace

TEST_CASE("the XDMF sidecar lists the fluid's frames and only the fields XDMF can describe") {
    const auto dir = std::filesystem::temp_directory_path() / ("sphfsi-xdmf-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const auto file = dir / "record.h5";
    {
        sphfsi::coordinator::Recorder rec(file, sphfsi::coordinator::RunMetadata{});
        const std::uint64_t n = 5;
        Fields fluid;
        fluid["position"] = F64Array({n, 3}, std::vector<double>(3 * n, 0.5));
        fluid["pressure"] = F64Array({n}, std::vector<double>(n, 1.0));
        fluid["stress"] = F64Array({n, 2, 2}, std::vector<double>(4 * n, 2.0));
        rec.append_frame("fluid", 0.0, fluid);
        rec.append_frame("fluid", 0.1, fluid);
        const std::string text = read_text(dir / "record.xdmf");
        CHECK(count(text, "GeometryType=\"XYZ\"") == 2);
        CHECK(count(text, "Attribute Name=\"pressure\"") == 2);
        CHECK(count(text, "stress") == 0);  // in record.h5, not in the sidecar
        CHECK(text.find("Dimensions=\"2 5 3\"") != std::string::npos);  // position's dataset, as it is
        // pressure's rows are 1-D: its dataset is (frames, n), and was declared (frames, n, 1) (a review).
        CHECK(text.find("Dimensions=\"2 5\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">record.h5:/frames/fluid/pressure") != std::string::npos);
        CHECK(text.find("Dimensions=\"2 5 1\"") == std::string::npos);

        Fields structure;  // a foreign structure sending positions too
        structure["position"] = F64Array({3, 2}, std::vector<double>(6, 0.0));
        rec.append_frame("structure", 0.1, structure);
        CHECK(read_text(dir / "record.xdmf") == text);
    }
    std::filesystem::remove_all(dir);
}

TEST_CASE("the sidecar is rewritten at every frame up to the 100th, then at every (frames / 100)-th, and at the status") {
    // Rewritten whole at every frame, it cost writes growing with the square of the frame count (a review,
    // 2026-11-27). After a SIGKILL it may miss the latest frames, under 1 % of them; record.h5 holds them.
    const auto dir = std::filesystem::temp_directory_path() / ("sphfsi-xdmf-throttle-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    {
        sphfsi::coordinator::Recorder rec(dir / "record.h5", sphfsi::coordinator::RunMetadata{});
        Fields fluid;
        fluid["position"] = F64Array({2, 2}, std::vector<double>(4, 0.5));
        auto listed = [&] { return count(read_text(dir / "record.xdmf"), "<Time Value="); };
        for (int k = 0; k < 100; ++k) rec.append_frame("fluid", 0.01 * k, fluid);
        CHECK(listed() == 100);
        rec.append_frame("fluid", 1.00, fluid);  // 101: 101 % 1 == 0
        CHECK(listed() == 101);
        for (int k = 101; k < 201; ++k) rec.append_frame("fluid", 0.01 * k, fluid);
        CHECK(listed() == 200);  // 201 % 2 != 0: not rewritten at the 201st
        CHECK(rec.set_status("completed") == "completed");
        CHECK(listed() == 201);
        // The last write can fail too (here a directory stands where its temporary file goes): the run has not
        // completed then, and the status says why.
        std::filesystem::create_directories(dir / "record.xdmf.tmp");
        CHECK(rec.set_status("completed").rfind("failed: cannot write the XDMF sidecar", 0) == 0);
        CHECK(rec.set_status("interrupted at t = 1 s") == "interrupted at t = 1 s");  // a stop keeps its own cause
    }
    std::filesystem::remove_all(dir);
}
