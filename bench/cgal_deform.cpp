// Comparison benchmark (optional; built only when Debian's libcgal-dev and
// libeigen3-dev are installed): CGAL's Surface_mesh_deformation (ARAP
// spokes = ORIGINAL_ARAP, spokes-and-rims = SPOKES_AND_RIMS) on the same
// mesh and handles as bench_stretch_bend_edit: the lowest 10% of the
// vertices by y fixed (left out of the region of interest), the highest 10%
// moved by 10% of the height along x. Prints the same TSV columns.
//
//   cgal_deform MESH.obj [ITERATIONS]
#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_deformation.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
using VD = Mesh::Vertex_index;

static double now()
{
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

// Minimal OBJ reader (v and f lines, polygons fanned into triangles).
static bool read_obj(const char *path, Mesh &mesh)
{
    std::ifstream in(path);
    if (!in) return false;
    std::vector<VD> vs;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream ss(line);
        std::string tag;
        ss >> tag;
        if (tag == "v") {
            double x, y, z;
            ss >> x >> y >> z;
            vs.push_back(mesh.add_vertex(Point(x, y, z)));
        } else if (tag == "f") {
            std::vector<VD> f;
            std::string tok;
            while (ss >> tok) f.push_back(vs.at(static_cast<size_t>(std::stol(tok.substr(0, tok.find('/'))) - 1)));
            for (size_t k = 1; k + 1 < f.size(); ++k)
                if (mesh.add_face(f[0], f[k], f[k + 1]) == Mesh::null_face()) return false;
        }
    }
    return true;
}

template <CGAL::Deformation_algorithm_tag TAG>
static void run(const char *name, const char *path, int iterations)
{
    Mesh mesh;
    if (!read_obj(path, mesh)) {
        std::fprintf(stderr, "cgal_deform: cannot read %s\n", path);
        std::exit(1);
    }
    const size_t nv = mesh.number_of_vertices();
    std::vector<VD> order(mesh.vertices().begin(), mesh.vertices().end());
    // Same rule as bench_stretch_bend_edit.c: sort by (y, index).
    std::sort(order.begin(), order.end(), [&](VD a, VD b) {
        double ya = mesh.point(a).y(), yb = mesh.point(b).y();
        return ya != yb ? ya < yb : a < b;
    });
    const double height = mesh.point(order.back()).y() - mesh.point(order.front()).y();
    const size_t tenth = nv / 10;

    using Deform = CGAL::Surface_mesh_deformation<Mesh, CGAL::Default, CGAL::Default, TAG>;
    double t0 = now();
    Deform dm(mesh);
    // Fixed vertices stay outside the region of interest; moved ones are controls.
    for (size_t k = tenth; k < nv; ++k) dm.insert_roi_vertex(order[k]);
    for (size_t k = nv - tenth; k < nv; ++k) dm.insert_control_vertex(order[k]);
    bool ok = dm.preprocess();
    for (size_t k = nv - tenth; k < nv; ++k) {
        const Point &p = mesh.point(order[k]);
        dm.set_target_position(order[k], Point(p.x() + 0.1 * height, p.y(), p.z()));
    }
    double setup = now() - t0;
    if (!ok) {
        std::printf("cgal\t%s\t%zu\t%zu\tpreprocess failed\n", name, nv, mesh.number_of_faces());
        return;
    }
    // One iteration per call (the state carries over), to report the mean
    // and the fastest iteration as bench_stretch_bend_edit does.
    double total = 0.0, best = 1e30;
    for (int k = 0; k < iterations; ++k) {
        t0 = now();
        dm.deform(1u, 0.0);
        double dt = now() - t0;
        total += dt;
        best = std::min(best, dt);
    }
    std::printf("cgal\t%s\t%zu\t%zu\t%zu\t%d\t%.1f\t%.2f\t%.2f\n", name, nv, mesh.number_of_faces(), 2 * tenth,
                iterations, 1e3 * setup, 1e3 * total / iterations, 1e3 * best);
    std::fflush(stdout);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: cgal_deform MESH.obj [ITERATIONS]\n");
        return 1;
    }
    int iterations = argc > 2 ? std::atoi(argv[2]) : 20;
    std::printf("method\tenergy\tV\tF\thandles\titerations\tsetup_ms\tms_per_iteration\tmin_ms_per_iteration\n");
    run<CGAL::ORIGINAL_ARAP>("arap", argv[1], iterations);
    run<CGAL::SPOKES_AND_RIMS>("arap-rims", argv[1], iterations);
    return 0;
}
