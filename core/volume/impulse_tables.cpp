#include "volume/impulse_tables.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include <Imath/half.h>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/file_io.h"
#include "base/hash.h"

namespace freqlab {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr const char* kMagic = "freqlab-impulse-tables";

void put(std::vector<float>& out, const ZhVector& z) {
    for (double v : z) out.push_back(float(v));
}

ZhVector take(const float*& p) {
    ZhVector z;
    for (double& v : z) v = double(*p++);
    return z;
}

size_t payload_floats(int bounces) {
    const size_t bins = ZhDistanceTable::kBins, order = kImpulseOrder;
    return 2 * (kSingleColumns * bins * order + bins) + bins * kShiftBins * 2 +
           size_t(bounces) * bins * order + size_t(bounces + 1) * bins +
           2 * size_t(bounces) * bins * order;
}

// The area responses are stored as IEEE half floats (Imath): relative rounding 2.4e-4, 20x
// below the 0.5 % the remaps are held to, and the file stays under 2 MB.
size_t payload_halves() {
    return size_t(ZhDistanceTable::kBins) * kShiftBins * kGNodeCount * kImpulseOrder;
}

}  // namespace

ImpulseTables ImpulseTables::build(int bounces, Progress* progress) {
    ImpulseTables t;
    if (progress) progress->begin_stage("point single scattering", 1);
    t.point_single_ = std::make_shared<SingleScatterTable>(SingleScatterTable::Emitter::Point);
    if (progress) progress->begin_stage("directional single scattering", 1);
    t.directional_single_ =
        std::make_shared<SingleScatterTable>(SingleScatterTable::Emitter::Directional);
    if (progress) progress->begin_stage("multiple scattering", 1);
    t.point_multiple_ = std::make_shared<PointMultipleScatter>(bounces);
    if (progress) progress->begin_stage("directional multiple scattering", 1);
    t.directional_multiple_ = std::make_shared<SlabMultipleScatter>(bounces);
    if (progress) progress->begin_stage("directional multiple scattering, slab bottom", 1);
    t.directional_multiple_bottom_ =
        std::make_shared<SlabMultipleScatter>(build_slab_bottom_multiple_scatter(bounces));
    if (progress) progress->begin_stage("area single scattering", 1);
    t.area_single_ = std::make_shared<AreaSingleScatterTable>();
    return t;
}

void ImpulseTables::save(const fs::path& path) const {
    std::vector<float> payload;
    for (const SingleScatterTable* table : {point_single_.get(), directional_single_.get()}) {
        for (const auto& column : table->canonical_terms())
            for (const ZhVector& z : column) put(payload, z);
        for (double e : table->error()) payload.push_back(float(e));
    }
    std::vector<Imath::half> halves;
    for (const AreaTableRow& row : area_single_->rows())
        for (int s = 0; s < kShiftBins; ++s) {
            for (const ZhVector& z : row.zh[size_t(s)])
                for (double v : z) halves.emplace_back(float(v));
            payload.push_back(float(row.tilt[size_t(s)]));
            payload.push_back(float(row.error[size_t(s)]));
        }
    const int bounces = point_multiple_->bounces();
    for (int k = 1; k <= bounces; ++k)
        for (const ZhVector& z : point_multiple_->zh()[size_t(k)]) put(payload, z);
    for (int k = 0; k <= bounces; ++k)
        for (double v : point_multiple_->fluence_scaled()[size_t(k)]) payload.push_back(float(v));
    for (const SlabMultipleScatter* slab :
         {directional_multiple_.get(), directional_multiple_bottom_.get()})
        for (int k = 1; k <= bounces; ++k)
            for (const ZhVector& z : slab->zh()[size_t(k)]) put(payload, z);
    if (payload.size() != payload_floats(bounces))
        throw Error(path.string(), "payload", "internal: table layout and size disagree");
    std::string bytes(reinterpret_cast<const char*>(payload.data()),
                      payload.size() * sizeof(float));
    bytes.append(reinterpret_cast<const char*>(halves.data()), halves.size() * sizeof(Imath::half));
    const json header = {{"version", kFormatVersion},
                         {"order", kImpulseOrder},
                         {"bins", ZhDistanceTable::kBins},
                         {"min_d", ZhDistanceTable::kMinD},
                         {"max_d", ZhDistanceTable::kMaxD},
                         {"phase_terms", kPhaseTerms},
                         {"g_nodes", kGNodes},
                         {"g_range", kGRange},
                         {"g_inner", kGInner},
                         {"g_panel_edges", kGPanelEdges},
                         {"shift_bins", kShiftBins},
                         {"bounces", bounces},
                         {"payload_floats", payload.size()},
                         {"payload_halves", halves.size()},
                         {"checksum", std::to_string(fnv1a_words(bytes.data(), bytes.size()))}};
    if (path.has_parent_path()) fs::create_directories(path.parent_path());
    write_text_atomically(path, std::string(kMagic) + "\n" + header.dump() + "\n" + bytes);
}

ImpulseTables ImpulseTables::load(const fs::path& path) {
    const std::string file = path.string();
    const std::string text = read_text_file(path);
    const size_t l1 = text.find('\n'), l2 = l1 == std::string::npos ? l1 : text.find('\n', l1 + 1);
    if (l1 == std::string::npos || l2 == std::string::npos || text.compare(0, l1, kMagic) != 0)
        throw Error(file, "header",
                    "not a freqlab impulse-table file (regenerate with `freqlab tables`)");
    const json h = json::parse(text.substr(l1 + 1, l2 - l1 - 1), nullptr, false);
    if (h.is_discarded() || !h.is_object())
        throw Error(file, "header", "malformed JSON header; expected an object");
    // A header field of another type is the same error as a wrong value (json::value() would
    // throw nlohmann's type_error, naming no file).
    auto integer = [&](const char* field) -> long long {
        if (!h.contains(field)) return -1;
        if (!h[field].is_number_integer())
            throw Error(file, field, "expected an integer, got " + h[field].dump());
        return h[field].get<long long>();
    };
    auto expect = [&](const char* field, double value) {
        if (!h.contains(field) || !h[field].is_number() || h[field].get<double>() != value)
            throw Error(
                file, field,
                "expected " + std::to_string(value) + ", got " +
                    (h.contains(field) ? h[field].dump() : "nothing") +
                    " (tables from another freqlab version: regenerate with `freqlab tables`)");
    };
    expect("version", kFormatVersion);
    expect("order", kImpulseOrder);
    expect("bins", ZhDistanceTable::kBins);
    expect("min_d", ZhDistanceTable::kMinD);
    expect("max_d", ZhDistanceTable::kMaxD);
    expect("phase_terms", kPhaseTerms);
    expect("g_nodes", kGNodes);
    expect("g_range", kGRange);
    expect("g_inner", kGInner);
    if (!h.contains("g_panel_edges") || h["g_panel_edges"] != json(kGPanelEdges))
        throw Error(file, "g_panel_edges",
                    "expected " + json(kGPanelEdges).dump() + ", got " +
                        (h.contains("g_panel_edges") ? h["g_panel_edges"].dump() : "nothing") +
                        " (tables from another freqlab version: regenerate with `freqlab tables`)");
    expect("shift_bins", kShiftBins);
    const long long bounces_field = integer("bounces");
    if (bounces_field < 1 || bounces_field > 1000)
        throw Error(file, "bounces", "expected 1 to 1000");
    const int bounces = int(bounces_field);
    const char* bytes_data = text.data() + l2 + 1;
    const size_t bytes_size = text.size() - l2 - 1;
    const size_t bins = ZhDistanceTable::kBins;
    const size_t expected = payload_floats(bounces);
    const size_t expected_bytes = expected * sizeof(float) + payload_halves() * sizeof(Imath::half);
    const long long floats_field = integer("payload_floats");
    const long long halves_field = integer("payload_halves");
    if (bytes_size != expected_bytes || floats_field != (long long)expected ||
        halves_field != (long long)payload_halves())
        throw Error(file, "payload",
                    "expected " + std::to_string(expected_bytes) + " bytes, the file has " +
                        std::to_string(bytes_size) + " (truncated?)");
    const std::string checksum =
        h.contains("checksum") && h["checksum"].is_string() ? h["checksum"].get<std::string>() : "";
    if (checksum != std::to_string(fnv1a_words(bytes_data, bytes_size)))
        throw Error(file, "checksum", "the payload does not match its checksum (damaged file)");
    std::vector<float> payload(expected);
    std::memcpy(payload.data(), bytes_data, expected * sizeof(float));
    std::vector<Imath::half> halves(payload_halves());
    std::memcpy(halves.data(), bytes_data + expected * sizeof(float),
                halves.size() * sizeof(Imath::half));
    // A checksum vouches for the bytes, not for the tables: a NaN written by a broken build
    // would reach every bake (issue "Reliability": NaN never leaks silently).
    for (size_t k = 0; k < payload.size(); ++k)
        if (!std::isfinite(payload[k]))
            throw Error(file, "payload", "value " + std::to_string(k) + " is not finite (NaN/Inf)");
    for (size_t k = 0; k < halves.size(); ++k)
        if (!std::isfinite(float(halves[k])))
            throw Error(file, "payload",
                        "half value " + std::to_string(k) + " is not finite (NaN/Inf)");
    const Imath::half* hp = halves.data();
    const float* p = payload.data();
    ImpulseTables t;
    for (int e = 0; e < 2; ++e) {
        std::vector<std::vector<ZhVector>> terms(kSingleColumns, std::vector<ZhVector>(bins));
        for (auto& column : terms)
            for (ZhVector& z : column) z = take(p);
        std::vector<double> error(bins);
        for (double& v : error) v = double(*p++);
        const auto emitter =
            e == 0 ? SingleScatterTable::Emitter::Point : SingleScatterTable::Emitter::Directional;
        (e == 0 ? t.point_single_ : t.directional_single_) =
            std::make_shared<SingleScatterTable>(emitter, terms, std::move(error));
    }
    std::vector<AreaTableRow> rows(bins);
    for (AreaTableRow& row : rows)
        for (int s = 0; s < kShiftBins; ++s) {
            for (ZhVector& z : row.zh[size_t(s)])
                for (double& v : z) v = double(float(*hp++));
            row.tilt[size_t(s)] = double(*p++);
            row.error[size_t(s)] = double(*p++);
        }
    t.area_single_ = std::make_shared<AreaSingleScatterTable>(std::move(rows));
    std::vector<std::vector<ZhVector>> zh(size_t(bounces) + 1, std::vector<ZhVector>(bins));
    for (int k = 1; k <= bounces; ++k)
        for (ZhVector& z : zh[size_t(k)]) z = take(p);
    std::vector<std::vector<double>> fluence(size_t(bounces) + 1, std::vector<double>(bins));
    for (auto& row : fluence)
        for (double& v : row) v = double(*p++);
    t.point_multiple_ = std::make_shared<PointMultipleScatter>(std::move(fluence), std::move(zh));
    for (auto* slab_table : {&t.directional_multiple_, &t.directional_multiple_bottom_}) {
        std::vector<std::vector<ZhVector>> slab(size_t(bounces) + 1, std::vector<ZhVector>(bins));
        for (int k = 1; k <= bounces; ++k)
            for (ZhVector& z : slab[size_t(k)]) z = take(p);
        *slab_table = std::make_shared<SlabMultipleScatter>(std::move(slab));
    }
    return t;
}

fs::path ImpulseTables::default_path(int bounces) {
    return cache_directory() / "tables" /
           ("impulse_v" + std::to_string(kFormatVersion) + "_b" + std::to_string(bounces) + ".bin");
}

ImpulseTables ImpulseTables::cached(int bounces, std::string* path_used) {
    const fs::path path = default_path(bounces);
    if (path_used) *path_used = path.string();
    std::error_code ec;
    if (fs::is_regular_file(path, ec)) {
        try {
            return load(path);
        } catch (const Error&) {
            // A stale or damaged cache is rebuilt, not fatal.
        }
    }
    ImpulseTables t = build(bounces);
    try {
        t.save(path);
        // What the file holds, not what was built: the file stores floats (the area tables
        // halves), so a bake on freshly built double tables differed from every later bake
        // (found splitting a bake over MPI ranks, some of which load the file rank 0 wrote).
        return load(path);
    } catch (const std::exception&) {
    }
    return t;
}

ImpulseTables::Verification ImpulseTables::verify() const {
    Verification v;
    auto worst = [](const ZhVector& q, const ZhVector& ref) {
        double w = 0.0;
        for (int l = 0; l < kImpulseOrder; ++l)
            if (std::fabs(ref[size_t(l)]) > 1e-3 * std::fabs(ref[0]))
                w = std::max(w,
                             std::fabs(q[size_t(l)] - ref[size_t(l)]) / std::fabs(ref[size_t(l)]));
        return w;
    };
    for (double sigma_s : {0.2, 1.0, 4.0})
        for (double g : {-0.92, -0.7, -0.4, 0.0, 0.3, 0.75, 0.9, 0.95})
            for (double d : {0.1, 0.7, 2.0}) {
                const HomogeneousMedium m{sigma_s, 0.1, g};
                v.worst_point = std::max(v.worst_point,
                                         worst(point_single().single(m, d), point_single_zh(m, d)));
                v.worst_directional =
                    std::max(v.worst_directional,
                             worst(directional_single().single(m, d), directional_single_zh(m, d)));
                v.queries += 2;
            }
    return v;
}

}  // namespace freqlab
