// A C++ program whose vertex array grows through std::vector::push_back in
// build_mesh: every growth allocates a new buffer and frees the old one, so
// under an EMM_TAG rule with site=build_mesh the shim must end with exactly
// one tagged vertex array, the final buffer. The vector is left alive at
// exit on purpose, so the shim's exit log still sees it. 2,000 vertices:
// under the fault capture each growth's copy costs about one captured
// access a byte copied (322,499 for these, 6 s a run; 25 s for 20,000).
#include <cstdint>
#include <cstdio>
#include <vector>

struct Vert {
    uint32_t id;
    double xyz[3];
    int32_t pad[12];
};
static_assert(sizeof(Vert) == 80, "80-byte records");

static std::vector<Vert> *mesh;

__attribute__((noinline)) static void build_mesh(int n)
{
    mesh = new std::vector<Vert>;
    for (int i = 0; i < n; i++) {
        Vert v{};
        v.id = static_cast<uint32_t>(i);
        v.xyz[0] = i % 100;
        v.xyz[1] = i / 100;
        mesh->push_back(v);
    }
}

int main()
{
    build_mesh(2000);
    double s = 0;
    for (const Vert &v : *mesh)
        s += v.xyz[0] - v.xyz[1];
    std::printf("vertices: %zu\nsum: %.1f\n", mesh->size(), s);
    return 0;
}
