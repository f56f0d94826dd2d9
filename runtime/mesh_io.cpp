/* The OpenMesh bridge: PLY, STL and binary OFF files into a raw polygon soup
 * (mesh_io.h). Thesis §3.1 gives the model the soup becomes in mesh.c.
 *
 * OpenMesh's PolyMesh would build topology while reading and silently drop
 * faces it cannot insert (a third face on an edge, a "complex edge"), which is
 * a silently wrong mesh. So the importer below only collects positions and
 * corner lists, and mesh.c checks and builds. OpenMesh's readers are
 * process-wide singletons with mutable state and print to std::cerr and its
 * omerr()/omlog() streams, so reads are serialised by one lock, and for the
 * length of a read the streams are muted and std::cerr points at a sink. */
#include "mesh_io.h"

extern "C" {
#include "error.h" /* a C header without its own extern "C" */
}

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/IO/reader/OFFReader.hh>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <mutex>
#include <new>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace OpenMesh;

/* Collects what a reader hands over, nothing more. */
class RawImporter : public IO::BaseImporter {
public:
    std::vector<double> xyz;
    std::vector<int64_t> corner;
    std::vector<size_t> face_start{0};
    unsigned declared_v = 0, declared_f = 0;
    bool declared = false;

    VertexHandle add_vertex(const Vec3f &p) override { return push(p[0], p[1], p[2]); }
    VertexHandle add_vertex(const Vec3d &p) override { return push(p[0], p[1], p[2]); }
    VertexHandle add_vertex() override { return push(0, 0, 0); }
    void set_point(VertexHandle vh, const Vec3f &p) override
    {
        size_t i = static_cast<size_t>(vh.idx());
        if (vh.idx() >= 0 && i < xyz.size() / 3) {
            xyz[3 * i] = p[0];
            xyz[3 * i + 1] = p[1];
            xyz[3 * i + 2] = p[2];
        }
    }
    FaceHandle add_face(const VHandles &h) override
    {
        for (const VertexHandle &v : h)
            corner.push_back(v.idx());
        face_start.push_back(corner.size());
        return FaceHandle(static_cast<int>(face_start.size() - 2));
    }
    void reserve(unsigned nv, unsigned, unsigned nf) override
    {
        declared = true;
        declared_v = nv;
        declared_f = nf;
    }
    size_t n_vertices() const override { return xyz.size() / 3; }
    size_t n_faces() const override { return face_start.size() - 1; }
    size_t n_edges() const override { return 0; }

    /* Everything else a reader may offer is not part of emm's model. */
    HalfedgeHandle add_edge(VertexHandle, VertexHandle) override { return HalfedgeHandle(); }
    FaceHandle add_face(HalfedgeHandle) override { return FaceHandle(); }
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec2f> &) override {}
    void add_face_texcoords(FaceHandle, VertexHandle, const std::vector<Vec3f> &) override {}
    void set_face_texindex(FaceHandle, int) override {}
    void set_halfedge(VertexHandle, HalfedgeHandle) override {}
    void set_normal(VertexHandle, const Vec3f &) override {}
    void set_normal(VertexHandle, const Vec3d &) override {}
    void set_color(VertexHandle, const Vec3uc &) override {}
    void set_color(VertexHandle, const Vec4uc &) override {}
    void set_color(VertexHandle, const Vec3f &) override {}
    void set_color(VertexHandle, const Vec4f &) override {}
    void set_texcoord(VertexHandle, const Vec2f &) override {}
    void set_status(VertexHandle, const Attributes::StatusInfo &) override {}
    void set_next(HalfedgeHandle, HalfedgeHandle) override {}
    void set_face(HalfedgeHandle, FaceHandle) override {}
    void request_face_texcoords2D() override {}
    void set_texcoord(HalfedgeHandle, const Vec2f &) override {}
    void set_texcoord(VertexHandle, const Vec3f &) override {}
    void set_texcoord(HalfedgeHandle, const Vec3f &) override {}
    void set_status(HalfedgeHandle, const Attributes::StatusInfo &) override {}
    void set_color(EdgeHandle, const Vec3uc &) override {}
    void set_color(EdgeHandle, const Vec4uc &) override {}
    void set_color(EdgeHandle, const Vec3f &) override {}
    void set_color(EdgeHandle, const Vec4f &) override {}
    void set_status(EdgeHandle, const Attributes::StatusInfo &) override {}
    void set_normal(FaceHandle, const Vec3f &) override {}
    void set_normal(FaceHandle, const Vec3d &) override {}
    void set_color(FaceHandle, const Vec3uc &) override {}
    void set_color(FaceHandle, const Vec4uc &) override {}
    void set_color(FaceHandle, const Vec3f &) override {}
    void set_color(FaceHandle, const Vec4f &) override {}
    void set_status(FaceHandle, const Attributes::StatusInfo &) override {}
    void add_texture_information(int, std::string) override {}

private:
    VertexHandle push(double x, double y, double z)
    {
        xyz.push_back(x);
        xyz.push_back(y);
        xyz.push_back(z);
        return VertexHandle(static_cast<int>(xyz.size() / 3 - 1));
    }
};

std::mutex openmesh_lock;

/* Mutes OpenMesh for one read and restores what was there before, so a host
 * program that uses OpenMesh itself keeps its own settings. */
class Quiet {
public:
    Quiet()
        : err_(omerr().is_enabled()), log_(omlog().is_enabled()), out_(omout().is_enabled()),
          cerr_(std::cerr.rdbuf(&sink_))
    {
        omerr().disable();
        omlog().disable();
        omout().disable();
    }
    ~Quiet()
    {
        std::cerr.rdbuf(cerr_);
        if (err_) omerr().enable();
        if (log_) omlog().enable();
        if (out_) omout().enable();
    }

private:
    std::stringbuf sink_;
    bool err_, log_, out_;
    std::streambuf *cerr_;
};

std::string extension(const char *path)
{
    std::string p(path);
    size_t dot = p.find_last_of('.');
    size_t slash = p.find_last_of('/');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash))
        return "";
    std::string e = p.substr(dot + 1);
    for (char &c : e)
        c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return e;
}

/* A binary STL is an 80-byte header, a facet count and 50 bytes per facet.
 * OpenMesh takes a binary file whose size does not match for ASCII and reads
 * nothing, so a cut-short binary STL is caught here with its numbers. */
emm_status check_stl_size(const char *path, emm_error *err)
{
    std::ifstream in(path, std::ios::binary);
    char head[84];
    in.read(head, sizeof head);
    std::streamsize got = in.gcount();
    size_t skip = 0;
    while (skip < static_cast<size_t>(got) && std::isspace(static_cast<unsigned char>(head[skip])))
        skip++;
    bool says_solid = got - static_cast<std::streamsize>(skip) >= 5 &&
                      std::strncmp(head + skip, "solid", 5) == 0;
    if (got < 84)
        return says_solid ? EMM_OK
                          : emm_fail(err, EMM_ERR_FORMAT,
                                     "%s: not an STL file (too short for a binary STL and not ASCII STL)",
                                     path);
    in.seekg(0, std::ios::end);
    unsigned long long size = static_cast<unsigned long long>(in.tellg());
    uint32_t facets = static_cast<uint32_t>(static_cast<unsigned char>(head[80])) |
                      static_cast<uint32_t>(static_cast<unsigned char>(head[81])) << 8 |
                      static_cast<uint32_t>(static_cast<unsigned char>(head[82])) << 16 |
                      static_cast<uint32_t>(static_cast<unsigned char>(head[83])) << 24;
    unsigned long long want = 84ull + 50ull * facets;
    if (size == want || says_solid)
        return EMM_OK;
    if (size < want)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: truncated: header declares %u facets, file has %llu",
                        path, facets, (size - 84) / 50);
    return emm_fail(err, EMM_ERR_FORMAT,
                    "%s: malformed binary STL: header declares %u facets (%llu bytes), file has %llu bytes",
                    path, facets, want, size);
}

template <class T> T *copy_out(const std::vector<T> &v)
{
    if (v.empty())
        return nullptr;
    T *p = static_cast<T *>(std::malloc(v.size() * sizeof(T)));
    if (p)
        std::memcpy(p, v.data(), v.size() * sizeof(T));
    return p;
}

emm_status read_locked(const char *path, emm_raw_mesh *raw, emm_error *err)
{
    std::string ext = extension(path);
    const char *kind = ext == "ply" ? "PLY" : ext == "stl" ? "STL" : "OFF";
    if (ext == "stl") {
        emm_status st = check_stl_size(path, err);
        if (st != EMM_OK)
            return st;
    }

    RawImporter imp;
    IO::Options opt;
    bool ok, stream_failed = false, stream_ended = false;
    {
        Quiet quiet;
        if (ext == "ply" || ext == "off") {
            /* Reading from our own stream lets us see a number the reader
             * could not parse ("nan" in ASCII PLY) or data that ended early:
             * the readers carry on with stale values. The OFF reader reads a
             * stream with the header options its can_u_read(path) last
             * found, so that is called first (under the lock). */
            if (ext == "off" && !IO::OFFReader().can_u_read(path))
                return emm_fail(err, EMM_ERR_FORMAT, "%s: not a readable OFF file", path);
            std::ifstream in(path, std::ios::binary);
            if (!in)
                return emm_fail(err, EMM_ERR_IO, "%s: %s", path, std::strerror(errno));
            ok = IO::IOManager().read(in, ext, imp, opt);
            stream_failed = in.fail() || in.bad();
            stream_ended = in.eof();
        } else {
            ok = IO::IOManager().read(path, imp, opt);
        }
    }
    if ((!ok || stream_failed) && stream_ended && imp.declared)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: truncated: the data ends before the %u vertices and %u faces the header declares",
                        path, imp.declared_v, imp.declared_f);
    if (!ok)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: not a readable %s file (malformed or truncated)",
                        path, kind);
    if (stream_failed)
        return emm_fail(err, EMM_ERR_FORMAT,
                        "%s: malformed or truncated %s data: a value could not be read "
                        "(header declares %u vertices and %u faces)",
                        path, kind, imp.declared_v, imp.declared_f);
    if (imp.declared && imp.n_vertices() < imp.declared_v)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: truncated: header declares %u vertices, file has %zu",
                        path, imp.declared_v, imp.n_vertices());
    if (imp.declared && imp.n_faces() < imp.declared_f)
        return emm_fail(err, EMM_ERR_FORMAT, "%s: truncated: header declares %u faces, file has %zu",
                        path, imp.declared_f, imp.n_faces());

    raw->nv = imp.n_vertices();
    raw->nf = imp.n_faces();
    raw->xyz = copy_out(imp.xyz);
    raw->corner = copy_out(imp.corner);
    raw->face_start = copy_out(imp.face_start);
    raw->face_line = nullptr;
    raw->index_base = 0;
    if ((raw->nv && !raw->xyz) || (!imp.corner.empty() && !raw->corner) || !raw->face_start) {
        emm_raw_mesh_free(raw);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    }
    return EMM_OK;
}

} // namespace

extern "C" emm_status emm_read_openmesh(const char *path, emm_raw_mesh *raw, emm_error *err)
{
    *raw = emm_raw_mesh{};
    try {
        std::lock_guard<std::mutex> hold(openmesh_lock);
        return read_locked(path, raw, err);
    } catch (const std::bad_alloc &) {
        emm_raw_mesh_free(raw);
        return emm_fail(err, EMM_ERR_NOMEM, "%s: out of memory", path);
    } catch (const std::exception &e) {
        emm_raw_mesh_free(raw);
        return emm_fail(err, EMM_ERR_FORMAT, "%s: not a readable mesh file (%s)", path, e.what());
    }
}
