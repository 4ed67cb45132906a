// Benchmark and accuracy driver for the PositionBasedDynamics library's rod
// solvers, for comparison with groombake's physical model (issue 16).
// Not part of groombake's build or tests; compiled against the library's own
// sources by compare.sh (bench/reference/README.md).
//
//   driver bench  MODEL GROOM.obj STEPS THREADS[,..] SUBSTEPS ITERATIONS [REPEATS]
//   driver droop  MODEL LENGTH_M EDGES SUBSTEPS ITERATIONS [STIFFNESS]
//
// MODEL: direct   = DirectPositionBasedSolverForStiffRodsConstraint (one per strand)
//        sbt      = StretchBendingTwistingConstraint per joint (iterative)
//        cosserat = StretchShear + BendTwist constraints (Kugelstadt & Schoemer)
//
// Real hair: E 3.5 GPa, Poisson 0.3 (G = E / 2.6), radius 40 um, density
// 1300 kg/m^3, dt 1/360 s, gravity 9.8 m/s^2 along -Y. The root is clamped:
// a static anchor segment (rigid-body models) or a static anchor frame
// (Cosserat) continues the first edge behind the root vertex.

#include "Common/Common.h"
#include "Simulation/Simulation.h"
#include "Simulation/SimulationModel.h"
#include "Simulation/TimeManager.h"
#include "Simulation/TimeStepController.h"
#include "Utils/IndexedFaceMesh.h"
#include "Utils/Logger.h"
#include "Utils/Timing.h"
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include <omp.h>

INIT_LOGGING
INIT_TIMING

using namespace PBD;
using Strand = std::vector<Vector3r>;

static const Real E = 3.5e9;
static const Real G_SHEAR = 3.5e9 / 2.6;
static const Real RADIUS = 4.0e-5;
static const Real DENSITY = 1300.0;
static const Real GRAVITY = 9.8;
static const Real DT = 1.0 / 360.0;

enum class Model { Direct, Sbt, Cosserat };

static Model parse_model(const char *s) {
    if (!strcmp(s, "direct")) return Model::Direct;
    if (!strcmp(s, "sbt")) return Model::Sbt;
    if (!strcmp(s, "cosserat")) return Model::Cosserat;
    fprintf(stderr, "unknown model %s\n", s);
    exit(2);
}

// Polylines of a Wavefront OBJ (`v` and `l` lines), as groombake writes them.
static std::vector<Strand> read_obj(const char *path) {
    std::ifstream in(path);
    if (!in) { fprintf(stderr, "cannot read %s\n", path); exit(2); }
    std::vector<Vector3r> v;
    std::vector<Strand> strands;
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
            double x, y, z; s >> x >> y >> z; v.emplace_back(x, y, z);
        } else if (tag == "l") {
            Strand st; long i;
            while (s >> i) st.push_back(v[i > 0 ? i - 1 : (long)v.size() + i]);
            strands.push_back(st);
        }
    }
    return strands;
}

// Frames along a strand by parallel transport: rotation taking `axis` to
// each edge's direction.
static std::vector<Quaternionr> edge_frames(const Strand &p, const Vector3r &axis) {
    std::vector<Quaternionr> q;
    Vector3r from = axis;
    Quaternionr prev = Quaternionr::Identity();
    for (size_t i = 0; i + 1 < p.size(); i++) {
        Vector3r to = (p[i + 1] - p[i]).normalized();
        Quaternionr cur = Quaternionr::FromTwoVectors(from, to) * prev;
        cur.normalize();
        q.push_back(cur);
        prev = cur;
        from = to;
    }
    return q;
}

static void add_rigid_strand(SimulationModel &model, const Strand &p, Model kind) {
    static VertexData one_vertex;  // a rod segment has no render mesh
    static Utilities::IndexedFaceMesh no_mesh;
    if (one_vertex.size() == 0) { one_vertex.addVertex(Vector3r::Zero()); no_mesh.initMesh(1, 0, 0); }
    const Vector3r y(0, 1, 0);  // the library's rod axis is the segment's local y
    std::vector<Quaternionr> q = edge_frames(p, y);
    SimulationModel::RigidBodyVector &rbs = model.getRigidBodies();
    const Real area = M_PI * RADIUS * RADIUS;
    auto add_segment = [&](const Vector3r &a, const Vector3r &b, const Quaternionr &rot, bool dynamic) {
        const Real len = (b - a).norm();
        const Real mass = DENSITY * area * len;
        // Solid cylinder along y.
        const Real it = mass * (3.0 * RADIUS * RADIUS + len * len) / 12.0;
        const Vector3r inertia(it, 0.5 * mass * RADIUS * RADIUS, it);
        RigidBody *rb = new RigidBody();
        rb->initBody(mass, 0.5 * (a + b), inertia, rot, one_vertex, no_mesh);
        if (!dynamic) rb->setMass(0.0);
        rbs.push_back(rb);
        return (unsigned int)(rbs.size() - 1);
    };
    const Vector3r d0 = p[1] - p[0];
    const unsigned int anchor = add_segment(p[0] - d0, p[0], q[0], false);
    std::vector<unsigned int> seg;
    std::vector<Real> len;
    for (size_t i = 0; i + 1 < p.size(); i++) {
        seg.push_back(add_segment(p[i], p[i + 1], q[i], true));
        len.push_back((p[i + 1] - p[i]).norm());
    }
    std::vector<std::pair<unsigned int, unsigned int>> joints;
    std::vector<Vector3r> positions;
    std::vector<Real> radii, lengths, youngs, torsion;
    for (size_t j = 0; j < seg.size(); j++) {
        const unsigned int a = j == 0 ? anchor : seg[j - 1];
        // The root joint's Voronoi cell is half an edge (the anchor is the
        // clamp, not rod); PBD_FULL_ROOT_CELL=1 gives it a whole edge instead.
        const Real la = j == 0 ? (getenv("PBD_FULL_ROOT_CELL") ? len[0] : 0.0) : len[j - 1];
        joints.emplace_back(a, seg[j]);
        positions.push_back(p[j]);
        radii.push_back(RADIUS);
        lengths.push_back(0.5 * (la + len[j]));
        youngs.push_back(E);
        torsion.push_back(G_SHEAR);
    }
    if (kind == Model::Direct) {
        model.addDirectPositionBasedSolverForStiffRodsConstraint(joints, positions, radii, lengths, youngs, torsion);
    } else {
        for (size_t j = 0; j < joints.size(); j++)
            model.addStretchBendingTwistingConstraint(joints[j].first, joints[j].second, positions[j],
                                                      radii[j], lengths[j], youngs[j], torsion[j]);
    }
}

static void add_cosserat_strand(SimulationModel &model, const Strand &p, Real stiffness) {
    ParticleData &pd = model.getParticles();
    OrientationData &od = model.getOrientations();
    std::vector<Quaternionr> q = edge_frames(p, Vector3r(0, 0, 1));  // the Cosserat director d3 is local z
    const unsigned int p0 = pd.size();
    for (size_t i = 0; i < p.size(); i++) {
        pd.addVertex(p[i]);
        // The library's Cosserat demo gives every dynamic particle and frame a
        // mass of 1 (its stiffnesses are PBD factors in [0, 1], not moduli).
        pd.setMass(p0 + i, i == 0 ? 0.0 : 1.0);
    }
    const unsigned int q0 = od.size();
    od.addQuaternion(q[0]);  // static anchor frame behind the root
    od.setMass(q0, 0.0);
    for (size_t i = 0; i < q.size(); i++) {
        od.addQuaternion(q[i]);
        od.setMass(q0 + 1 + i, 1.0);
    }
    for (size_t i = 0; i < q.size(); i++)
        model.addStretchShearConstraint(p0 + i, p0 + i + 1, q0 + 1 + i, stiffness, stiffness, stiffness);
    for (size_t i = 0; i < q.size(); i++)
        model.addBendTwistConstraint(q0 + i, q0 + 1 + i, stiffness, stiffness, stiffness);
}

static SimulationModel *build(const std::vector<Strand> &strands, Model kind, unsigned substeps, unsigned iterations,
                              Real stiffness) {
    SimulationModel *model = new SimulationModel();
    model->init();
    Simulation *sim = Simulation::getCurrent();
    sim->setModel(model);
    Real g[3] = {0, -GRAVITY, 0};
    sim->setVecValue<Real>(Simulation::GRAVITATION, g);
    TimeManager::getCurrent()->setTimeStepSize(DT);
    TimeStepController *ts = (TimeStepController *)sim->getTimeStep();
    ts->setValue<unsigned int>(TimeStepController::NUM_SUB_STEPS, substeps);
    ts->setValue<unsigned int>(TimeStepController::MAX_ITERATIONS, iterations);
    ts->setValue<unsigned int>(TimeStepController::MAX_ITERATIONS_V, 0);  // no contacts
    for (const Strand &s : strands) {
        if (kind == Model::Cosserat) add_cosserat_strand(*model, s, stiffness);
        else add_rigid_strand(*model, s, kind);
    }
    return model;
}

static double cpu_seconds() {
    timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void step(SimulationModel &model) { Simulation::getCurrent()->getTimeStep()->step(model); }

// Tip position (the far end of the last segment / the last particle).
static Vector3r tip(SimulationModel &model, Model kind, Real edge) {
    if (kind == Model::Cosserat) {
        ParticleData &pd = model.getParticles();
        return pd.getPosition(pd.size() - 1);
    }
    RigidBody *rb = model.getRigidBodies().back();
    return rb->getPosition() + rb->getRotationMatrix() * Vector3r(0, 0.5 * edge, 0);
}

// Velocity damping for the static droop only (not in the timed runs): the
// library has no damping parameter for rods, so the driver scales the
// velocities after each step, critically damping the first mode.
static void damp(SimulationModel &model, Real factor) {
    for (RigidBody *rb : model.getRigidBodies()) {
        rb->getVelocity() *= factor;
        rb->getAngularVelocity() *= factor;
    }
    ParticleData &pd = model.getParticles();
    for (unsigned i = 0; i < pd.size(); i++) pd.getVelocity(i) *= factor;
    OrientationData &od = model.getOrientations();
    for (unsigned i = 0; i < od.size(); i++) od.getVelocity(i) *= factor;
}

static int droop(int argc, char **argv) {
    if (argc < 7) { fprintf(stderr, "droop MODEL LENGTH EDGES SUBSTEPS ITERATIONS [STIFFNESS]\n"); return 2; }
    Model kind = parse_model(argv[2]);
    const Real length = atof(argv[3]);
    const int edges = atoi(argv[4]);
    const unsigned substeps = atoi(argv[5]), iterations = atoi(argv[6]);
    const Real stiffness = argc > 7 ? atof(argv[7]) : 1.0;
    Strand s;
    for (int i = 0; i <= edges; i++) s.emplace_back(length * i / edges, 0, 0);
    omp_set_num_threads(1);
    SimulationModel *model = build({s}, kind, substeps, iterations, stiffness);
    const double ei = E * M_PI * std::pow(RADIUS, 4) / 4.0;
    const double w = DENSITY * M_PI * RADIUS * RADIUS * GRAVITY;
    const double omega1 = 1.8751 * 1.8751 * std::sqrt(ei / (w / GRAVITY * std::pow(length, 4)));
    const double seconds = 12.0 / omega1 + 0.5;
    const int steps = (int)std::lround(seconds / DT) * 3;  // three times groombake's settle time
    const Real factor = std::exp(-2.0 * omega1 * DT);
    double last = 0;
    for (int i = 0; i < steps; i++) {
        step(*model);
        damp(*model, factor);
        Vector3r t = tip(*model, kind, length / edges);
        if (!std::isfinite(t.y())) { printf("droop %s %g m %d edges %u x %u: non-finite\n", argv[2], length, edges, substeps, iterations); return 1; }
        last = -t.y();
    }
    Vector3r t = tip(*model, kind, length / edges);
    printf("droop model=%s length=%g edges=%d substeps=%u iterations=%u stiffness=%g steps=%d droop_m=%.6f tip_x=%.6f\n",
           argv[2], length, edges, substeps, iterations, stiffness, steps, last, t.x());
    return 0;
}

// Times STEPS steps per block; blocks go round THREADS (comma list) REPEATS
// times on one model (set up once). If PBD_BETWEEN is set, that shell
// command runs before each block (to interleave another program's runs).
static int bench(int argc, char **argv) {
    if (argc < 8) { fprintf(stderr, "bench MODEL GROOM.obj STEPS THREADS[,THREADS..] SUBSTEPS ITERATIONS [REPEATS]\n"); return 2; }
    Model kind = parse_model(argv[2]);
    std::vector<Strand> strands = read_obj(argv[3]);
    const int steps = atoi(argv[4]);
    std::vector<int> thread_list;
    { std::stringstream ts(argv[5]); std::string t; while (std::getline(ts, t, ',')) thread_list.push_back(atoi(t.c_str())); }
    const unsigned substeps = atoi(argv[6]), iterations = atoi(argv[7]);
    const int repeats = argc > 8 ? atoi(argv[8]) : 1;
    size_t vertices = 0;
    for (auto &s : strands) vertices += s.size();
    omp_set_num_threads(thread_list[0]);
    SimulationModel *model = build(strands, kind, substeps, iterations, 1.0);
    // Warm-up: the first step colours the constraint graph.
    step(*model);
    const char *between = getenv("PBD_BETWEEN");
    for (int r = 0; r < repeats; r++) {
        for (int threads : thread_list) {
            if (between) { setenv("PBD_THREADS", std::to_string(threads).c_str(), 1); fflush(stdout); if (system(between) != 0) fprintf(stderr, "PBD_BETWEEN failed\n"); }
            omp_set_num_threads(threads);
            step(*model);  // warm the thread pool
            double load[1] = {0};
            getloadavg(load, 1);
            const double c0 = cpu_seconds();
            const auto t0 = std::chrono::steady_clock::now();
            for (int i = 0; i < steps; i++) step(*model);
            const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            const double cpu = cpu_seconds() - c0;
            Vector3r t = kind == Model::Cosserat ? model->getParticles().getPosition(model->getParticles().size() - 1)
                                                 : model->getRigidBodies().back()->getPosition();
            const double per = (double)vertices * steps;
            printf("{\"program\":\"pbd\",\"model\":\"%s\",\"strands\":%zu,\"vertices\":%zu,\"threads\":%d,\"substeps\":%u,"
                   "\"iterations\":%u,\"steps\":%d,\"seconds\":%.3f,\"ns_per_vertex_step\":%.1f,"
                   "\"cpu_ns_per_vertex_step\":%.1f,\"load_average\":%.2f,\"finite\":%s}\n",
                   argv[2], strands.size(), vertices, threads, substeps, iterations, steps, wall, 1e9 * wall / per,
                   1e9 * cpu / per, load[0], std::isfinite(t.sum()) ? "true" : "false");
            fflush(stdout);
        }
    }
    return 0;
}

int main(int argc, char **argv) {
    Utilities::logger.addSink(std::shared_ptr<Utilities::ConsoleSink>(new Utilities::ConsoleSink(Utilities::LogLevel::WARN)));
    if (argc > 1 && !strcmp(argv[1], "bench")) return bench(argc, argv);
    if (argc > 1 && !strcmp(argv[1], "droop")) return droop(argc, argv);
    fprintf(stderr, "usage: driver bench|droop ...\n");
    return 2;
}
