// IPOPT driven directly on the NMPC's compiled NLP library, without CasADi's interface.
//
// Used by bench/bench_ipopt_floor.py to measure how little processor time IPOPT (with
// MUMPS, as shipped in the casadi wheel) can spend on one of our NMPC solves, in two ways:
//
//   fresh  a new IpoptApplication for every solve (what CasADi's nlpsol does)
//   reuse  one IpoptApplication kept between solves (ReOptimizeTNLP: options, journal
//          and algorithm objects are not set up again)
//
// Usage: ipopt_floor LIBRARY CALLS_FILE REPEATS fresh|reuse [OPTION=VALUE ...]
//        ipopt_floor --check [OPTION=VALUE ...]   (only sets the options: exit 2 if refused)
//
// CALLS_FILE holds recorded solves, each as eight arrays (x0, p, lbx, ubx, lbg, ubg,
// lam_x0, lam_g0), every array an int64 length followed by that many doubles, after an
// int64 count of solves. IPOPT's options are those of the NMPC with warm-started duals;
// OPTION=VALUE pairs are set after them (an integer, a number or a string, as written).
// Prints one line per solve: mean processor seconds per solve over REPEATS, IPOPT's
// status, iterations, and the solution x (for the comparison with CasADi's).
#include <coin-or/IpIpoptApplication.hpp>
#include <coin-or/IpSolveStatistics.hpp>
#include <coin-or/IpTNLP.hpp>
#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

using namespace Ipopt;

typedef long long casadi_int;  // the library's casadi_int_size is checked to be 8
typedef int (*Eval)(const double**, double**, casadi_int*, double*, int);
typedef int (*WorkSizes)(casadi_int*, casadi_int*, casadi_int*, casadi_int*);
typedef const casadi_int* (*SparsityOut)(casadi_int);
typedef void (*Incref)(void);
typedef int (*IntSize)(void);

[[noreturn]] static void fail(const std::string& what) {
  std::fprintf(stderr, "ipopt_floor: %s\n", what.c_str());
  std::exit(2);
}

// One generated CasADi function: its entry point, output sparsity and work buffers.
struct Generated {
  Eval eval = nullptr;
  SparsityOut sparsity_out = nullptr;
  std::vector<const double*> arg;
  std::vector<double*> res;
  std::vector<casadi_int> iw;
  std::vector<double> w;

  void load(void* library, const std::string& name) {
    eval = (Eval)dlsym(library, name.c_str());
    sparsity_out = (SparsityOut)dlsym(library, (name + "_sparsity_out").c_str());
    WorkSizes sizes = (WorkSizes)dlsym(library, (name + "_work").c_str());
    Incref incref = (Incref)dlsym(library, (name + "_incref").c_str());
    if (!eval || !sparsity_out || !sizes) fail("the library has no function " + name);
    if (incref) incref();
    casadi_int n_arg, n_res, n_iw, n_w;
    sizes(&n_arg, &n_res, &n_iw, &n_w);
    arg.resize(n_arg);
    res.resize(n_res);
    iw.resize(n_iw);
    w.resize(n_w);
  }
  bool call() { return eval(arg.data(), res.data(), iw.data(), w.data(), 0) == 0; }
};

struct Solve {
  std::vector<double> x0, p, lbx, ubx, lbg, ubg, lam_x0, lam_g0, x;
};

static std::vector<double> read_array(FILE* file) {
  long long n = 0;
  if (std::fread(&n, 8, 1, file) != 1 || n < 0) fail("truncated calls file");
  std::vector<double> values(n);
  if (std::fread(values.data(), 8, n, file) != (size_t)n) fail("truncated calls file");
  return values;
}

// Triplets (row, column) of a CasADi compressed-column sparsity pattern.
static void triplets(const casadi_int* sparsity, Index* rows, Index* cols, bool transpose) {
  casadi_int ncol = sparsity[1];
  const casadi_int* colind = sparsity + 2;
  const casadi_int* row = colind + ncol + 1;
  int k = 0;
  for (casadi_int c = 0; c < ncol; ++c)
    for (casadi_int e = colind[c]; e < colind[c + 1]; ++e, ++k) {
      rows[k] = (Index)(transpose ? c : row[e]);
      cols[k] = (Index)(transpose ? row[e] : c);
    }
}

class CompiledNLP : public TNLP {
 public:
  CompiledNLP(void* library) {
    objective_.load(library, "nlp_f");
    constraints_.load(library, "nlp_g");
    gradient_.load(library, "nlp_grad_f");
    jacobian_.load(library, "nlp_jac_g");
    hessian_.load(library, "nlp_hess_l");
    jacobian_sparsity_ = jacobian_.sparsity_out(1);
    hessian_sparsity_ = hessian_.sparsity_out(0);  // upper triangle, column-major
  }
  Solve* solve = nullptr;

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac, Index& nnz_h, IndexStyleEnum& style) override {
    n = (Index)solve->x0.size();
    m = (Index)solve->lbg.size();
    nnz_jac = (Index)jacobian_sparsity_[2 + jacobian_sparsity_[1]];
    nnz_h = (Index)hessian_sparsity_[2 + hessian_sparsity_[1]];
    style = C_STYLE;
    buffer_.resize(std::max<size_t>(m, 1));
    return true;
  }
  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    std::copy_n(solve->lbx.data(), n, x_l);
    std::copy_n(solve->ubx.data(), n, x_u);
    std::copy_n(solve->lbg.data(), m, g_l);
    std::copy_n(solve->ubg.data(), m, g_u);
    return true;
  }
  // The bound multipliers from CasADi's signed lam_x, as its IPOPT interface passes them.
  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_l, Number* z_u, Index m,
                          bool init_lambda, Number* lambda) override {
    if (init_x) std::copy_n(solve->x0.data(), n, x);
    if (init_z)
      for (Index i = 0; i < n; ++i) {
        z_l[i] = std::max(0.0, -solve->lam_x0[i]);
        z_u[i] = std::max(0.0, solve->lam_x0[i]);
      }
    if (init_lambda) std::copy_n(solve->lam_g0.data(), m, lambda);
    return true;
  }
  bool eval_f(Index, const Number* x, bool, Number& f) override {
    objective_.arg[0] = x;
    objective_.arg[1] = solve->p.data();
    objective_.res[0] = &f;
    return objective_.call();
  }
  bool eval_grad_f(Index, const Number* x, bool, Number* grad) override {
    double f;
    gradient_.arg[0] = x;
    gradient_.arg[1] = solve->p.data();
    gradient_.res[0] = &f;
    gradient_.res[1] = grad;
    return gradient_.call();
  }
  bool eval_g(Index, const Number* x, bool, Index, Number* g) override {
    constraints_.arg[0] = x;
    constraints_.arg[1] = solve->p.data();
    constraints_.res[0] = g;
    return constraints_.call();
  }
  bool eval_jac_g(Index, const Number* x, bool, Index, Index, Index* rows, Index* cols, Number* values) override {
    if (values == nullptr) {
      triplets(jacobian_sparsity_, rows, cols, false);
      return true;
    }
    jacobian_.arg[0] = x;
    jacobian_.arg[1] = solve->p.data();
    jacobian_.res[0] = buffer_.data();
    jacobian_.res[1] = values;
    return jacobian_.call();
  }
  // IPOPT takes the lower triangle: CasADi's upper triangle, transposed.
  bool eval_h(Index, const Number* x, bool, Number obj_factor, Index, const Number* lambda, bool, Index,
              Index* rows, Index* cols, Number* values) override {
    if (values == nullptr) {
      triplets(hessian_sparsity_, rows, cols, true);
      return true;
    }
    hessian_.arg[0] = x;
    hessian_.arg[1] = solve->p.data();
    hessian_.arg[2] = &obj_factor;
    hessian_.arg[3] = lambda;
    hessian_.res[0] = values;
    return hessian_.call();
  }
  void finalize_solution(SolverReturn, Index n, const Number* x, const Number*, const Number*, Index, const Number*,
                         const Number*, Number, const IpoptData*, IpoptCalculatedQuantities*) override {
    solve->x.assign(x, x + n);
  }

 private:
  Generated objective_, constraints_, gradient_, jacobian_, hessian_;
  const casadi_int* jacobian_sparsity_;
  const casadi_int* hessian_sparsity_;
  std::vector<double> buffer_;
};

static std::vector<std::string> extra_options;

// Sets NAME=VALUE as an integer, a number or a string, whichever VALUE reads as whole.
static void set_option(OptionsList& options, const std::string& pair) {
  size_t equals = pair.find('=');
  if (equals == std::string::npos || equals == 0) fail("an IPOPT option must read NAME=VALUE, got " + pair);
  std::string name = pair.substr(0, equals), value = pair.substr(equals + 1);
  char* end = nullptr;
  long integer = std::strtol(value.c_str(), &end, 10);
  bool ok;
  if (!value.empty() && *end == '\0') {
    ok = options.SetIntegerValue(name, (Index)integer);
  } else {
    double number = std::strtod(value.c_str(), &end);
    ok = (!value.empty() && *end == '\0') ? options.SetNumericValue(name, number) : options.SetStringValue(name, value);
  }
  if (!ok) fail("IPOPT refused the option " + pair);
}

static SmartPtr<IpoptApplication> application() {
  SmartPtr<IpoptApplication> app = IpoptApplicationFactory();
  SmartPtr<OptionsList> options = app->Options();
  options->SetIntegerValue("print_level", 0);
  options->SetStringValue("sb", "yes");
  options->SetNumericValue("tol", 1e-6);
  options->SetIntegerValue("max_iter", 200);
  options->SetStringValue("mu_strategy", "adaptive");
  options->SetStringValue("warm_start_init_point", "yes");
  options->SetNumericValue("warm_start_bound_push", 1e-6);
  options->SetNumericValue("warm_start_mult_bound_push", 1e-6);
  options->SetNumericValue("mu_init", 1e-4);
  for (const std::string& pair : extra_options) set_option(*options, pair);
  if (app->Initialize("") != Solve_Succeeded) fail("IPOPT did not initialize");
  return app;
}

static double cpu_seconds() {
  timespec now;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return now.tv_sec + 1e-9 * now.tv_nsec;
}

int main(int argc, char** argv) {
  if (argc >= 2 && std::string(argv[1]) == "--check") {
    extra_options.assign(argv + 2, argv + argc);
    application();
    return 0;
  }
  if (argc < 5) fail("usage: ipopt_floor LIBRARY CALLS_FILE REPEATS fresh|reuse [OPTION=VALUE ...]");
  extra_options.assign(argv + 5, argv + argc);
  const std::string mode = argv[4];
  if (mode != "fresh" && mode != "reuse") fail("mode must be fresh or reuse, got " + mode);
  const int repeats = std::atoi(argv[3]);
  if (repeats < 1) fail("REPEATS must be at least 1");
  void* library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
  if (!library) fail(std::string("cannot load the library: ") + dlerror());
  std::string prefix = std::string(argv[1]);
  prefix = prefix.substr(prefix.find_last_of('/') + 1);
  prefix = prefix.substr(0, prefix.find('.'));
  IntSize int_size = (IntSize)dlsym(library, (prefix + "_casadi_int_size").c_str());
  if (int_size && int_size() != 8) fail("the library's casadi_int is not 64-bit");

  FILE* file = std::fopen(argv[2], "rb");
  if (!file) fail(std::string("cannot open ") + argv[2]);
  long long count = 0;
  if (std::fread(&count, 8, 1, file) != 1 || count < 1) fail("empty calls file");
  std::vector<Solve> solves(count);
  for (Solve& s : solves) {
    s.x0 = read_array(file);
    s.p = read_array(file);
    s.lbx = read_array(file);
    s.ubx = read_array(file);
    s.lbg = read_array(file);
    s.ubg = read_array(file);
    s.lam_x0 = read_array(file);
    s.lam_g0 = read_array(file);
  }
  std::fclose(file);

  SmartPtr<CompiledNLP> nlp = new CompiledNLP(library);
  SmartPtr<IpoptApplication> kept;
  if (mode == "reuse") {  // the structure is analysed once, before the timed solves
    kept = application();
    nlp->solve = &solves[0];
    kept->OptimizeTNLP(nlp);
  }
  for (Solve& s : solves) {
    nlp->solve = &s;
    ApplicationReturnStatus status = Solve_Succeeded;
    int iterations = -1;
    double start = cpu_seconds();
    for (int r = 0; r < repeats; ++r) {
      if (mode == "fresh") {
        SmartPtr<IpoptApplication> app = application();
        status = app->OptimizeTNLP(nlp);
        iterations = IsValid(app->Statistics()) ? app->Statistics()->IterationCount() : -1;
      } else {
        status = kept->ReOptimizeTNLP(nlp);
        iterations = IsValid(kept->Statistics()) ? kept->Statistics()->IterationCount() : -1;
      }
    }
    double seconds = (cpu_seconds() - start) / repeats;
    std::printf("%.9e %d %d", seconds, (int)status, iterations);
    for (double v : s.x) std::printf(" %.17g", v);
    std::printf("\n");
  }
  return 0;
}
