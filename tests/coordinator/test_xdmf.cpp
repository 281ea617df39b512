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

        Fields structure;  // a foreign structure sending positions too
        structure["position"] = F64Array({3, 2}, std::vector<double>(6, 0.0));
        rec.append_frame("structure", 0.1, structure);
        CHECK(read_text(dir / "record.xdmf") == text);
    }
    std::filesystem::remove_all(dir);
}
