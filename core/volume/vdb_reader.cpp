#include "volume/vdb_reader.h"

#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <new>

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include "base/error.h"
#include "base/file_io.h"
#include "volume/vdb_file_check.h"

namespace freqlab {

namespace {

void initialise_openvdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

}  // namespace

VdbDensity read_vdb_density(const std::string& file, const std::string& grid_name,
                            const std::string& scene_file, const std::string& field) {
    initialise_openvdb();
    if (!std::filesystem::exists(file))
        throw Error(scene_file, field + ".file", "VDB file '" + file + "' does not exist");
    // Sizes the file declares beyond its own length are refused before OpenVDB allocates them.
    if (const std::string problem = check_vdb_layout(file); !problem.empty())
        throw Error(scene_file, field + ".file", "cannot read VDB file '" + file + "': " + problem);
    openvdb::GridBase::Ptr base;
    std::vector<std::string> names;
    try {
        // A stream that throws on a short read: OpenVDB's readers do not check the stream, so
        // a truncated file would leave string and array sizes uninitialised (fuzz_vdb: random
        // multi-GB allocations). No delayed load: its index trusts the file.
        std::ifstream in(file, std::ios::binary);
        in.exceptions(std::ios::failbit | std::ios::badbit);
        openvdb::io::Stream vdb(in, /*delayLoad=*/false);
        for (const auto& g : *vdb.getGrids()) {
            names.push_back(g->getName());
            if (!base && g->getName() == grid_name) base = g;
        }
    } catch (const openvdb::Exception& e) {
        throw Error(scene_file, field + ".file",
                    "cannot read VDB file '" + file + "': " + e.what());
    } catch (const std::ios_base::failure&) {
        throw Error(scene_file, field + ".file",
                    "cannot read VDB file '" + file +
                        "': it ends before the grid it declares does (truncated or damaged?)");
    } catch (const std::bad_alloc&) {
        // OpenVDB allocates the block sizes a file declares (fuzz_vdb: 2^60 bytes).
        throw Error(scene_file, field + ".file",
                    "cannot read VDB file '" + file +
                        "': it declares more memory than this machine has (damaged file?)");
    } catch (const std::exception& e) {  // std::ios_base::failure, length_error, ...
        throw Error(scene_file, field + ".file",
                    "cannot read VDB file '" + file + "': " + e.what());
    }
    if (!base) {
        std::string list;
        for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
        throw Error(scene_file, field + ".grid",
                    "VDB file '" + file + "' has no grid named '" + grid_name +
                        "' (it has: " + (list.empty() ? "none" : list) + ")");
    }
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!grid)
        throw Error(scene_file, field + ".grid",
                    "grid '" + grid_name + "' is a " + base->valueType() +
                        " grid; expected a float density grid");
    if (!grid->hasUniformVoxels() || !grid->transform().isLinear())
        throw Error(scene_file, field + ".grid",
                    "grid '" + grid_name +
                        "' has a non-uniform or non-linear transform; expected "
                        "cubic voxels");
    const openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
    if (box.empty())
        throw Error(scene_file, field + ".grid", "grid '" + grid_name + "' has no active voxel");
    // The extent in 64 bits first: Coord::dim() overflows int for a box across the index space.
    double span = 1.0;
    for (int a = 0; a < 3; ++a) span *= double(int64_t(box.max()[a]) - box.min()[a] + 1);
    if (span > double(1 << 27))
        throw Error(scene_file, field + ".grid",
                    "grid '" + grid_name + "' spans more than 2^27 voxels; expected a smaller one");
    const openvdb::Coord dim = box.dim();
    VdbDensity out;
    out.resolution = ivec3(dim.x(), dim.y(), dim.z());
    out.voxels.resize(size_t(dim.x()) * dim.y() * dim.z());
    auto accessor = grid->getConstAccessor();
    for (int z = 0; z < dim.z(); ++z)
        for (int y = 0; y < dim.y(); ++y)
            for (int x = 0; x < dim.x(); ++x) {
                const openvdb::Coord c = box.min() + openvdb::Coord(x, y, z);
                const float v = accessor.getValue(c);
                if (!std::isfinite(v) || v < 0.0f)
                    throw Error(scene_file, field + ".grid",
                                "grid '" + grid_name + "' has voxel (" + std::to_string(c.x()) +
                                    ", " + std::to_string(c.y()) + ", " + std::to_string(c.z()) +
                                    ") = " + std::to_string(v) +
                                    "; expected a finite density >= 0");
                out.voxels[(size_t(z) * dim.y() + y) * dim.x() + x] = v;
            }
    // Voxel (i, j, k) of a cell-centred VDB covers index space [i - 0.5, i + 0.5].
    const openvdb::Vec3d lo = grid->indexToWorld(openvdb::Vec3d(box.min().asVec3d()) - 0.5);
    const openvdb::Vec3d hi = grid->indexToWorld(openvdb::Vec3d(box.max().asVec3d()) + 0.5);
    out.box_min =
        vec3(std::min(lo.x(), hi.x()), std::min(lo.y(), hi.y()), std::min(lo.z(), hi.z()));
    out.box_max =
        vec3(std::max(lo.x(), hi.x()), std::max(lo.y(), hi.y()), std::max(lo.z(), hi.z()));
    for (int a = 0; a < 3; ++a)
        if (!std::isfinite(out.box_min[a]) || !std::isfinite(out.box_max[a]) ||
            !(out.box_max[a] > out.box_min[a]) || std::fabs(out.box_min[a]) > 1e12f ||
            std::fabs(out.box_max[a]) > 1e12f)
            throw Error(scene_file, field + ".grid",
                        "grid '" + grid_name +
                            "' has a voxel size or offset whose world box is degenerate or "
                            "beyond 1e12 units; expected a finite, non-empty box");
    return out;
}

void write_vdb_density(const std::string& file, const std::string& grid_name,
                       const VdbDensity& density) {
    initialise_openvdb();
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(grid_name);
    const vec3 voxel = (density.box_max - density.box_min) / vec3(density.resolution);
    if (std::abs(voxel.x - voxel.y) > 1e-5f * voxel.x ||
        std::abs(voxel.x - voxel.z) > 1e-5f * voxel.x)
        throw Error(file, grid_name, "expected cubic voxels to write a VDB grid");
    auto transform = openvdb::math::Transform::createLinearTransform(voxel.x);
    // Cell centres at box_min + (i + 0.5) voxel.
    transform->postTranslate(
        openvdb::Vec3d(density.box_min.x, density.box_min.y, density.box_min.z) + 0.5 * voxel.x);
    grid->setTransform(transform);
    auto accessor = grid->getAccessor();
    const ivec3 r = density.resolution;
    for (int z = 0; z < r.z; ++z)
        for (int y = 0; y < r.y; ++y)
            for (int x = 0; x < r.x; ++x) {
                const float v = density.voxels[(size_t(z) * r.y + y) * r.x + x];
                if (v != 0.0f) accessor.setValue(openvdb::Coord(x, y, z), v);
            }
    const std::string tmp = file + ".tmp";
    openvdb::io::File out(tmp);
    out.write({grid});
    out.close();
    std::filesystem::rename(tmp, file);
}

}  // namespace freqlab
