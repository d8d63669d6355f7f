// Queries allocate nothing: every buffer lives in the workspace (engine.h). Checked by counting
// operator new calls on this thread while a query runs (the replacement operators below serve
// the whole test program; they only count when armed).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <new>
#include <string>
#include <vector>

#include "neraf/neraf_rt.h"
#include "random_model.h"

namespace {
thread_local bool armed = false;
thread_local int allocations = 0;
}  // namespace

void* operator new(size_t n) {
  if (armed) ++allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }

namespace fs = std::filesystem;

// A float32 model, and a bf16 one (its trunk in bfloat16 where the CPU has AMX or AVX512-BF16).
static void expect_queries_allocate_nothing(bool bf16) {
  std::string t = (fs::temp_directory_path() / "neraf_rt_alloc_XXXXXX").string();
  const fs::path dir = ::mkdtemp(t.data());
  const std::string path = (dir / "m.nrf").string();
  neraf::rt::testing::RandomModelOptions o;
  o.relative_geometry = true;
  o.bf16 = bf16;
  neraf::rt::write_model_file(path, neraf::rt::testing::random_model(o));
  neraf_model* model = nullptr;
  ASSERT_EQ(neraf_model_load(path.c_str(), &model), NERAF_OK);
  neraf_model_info info;
  neraf_model_get_info(model, &info);
  neraf_workspace* ws = nullptr;
  ASSERT_EQ(neraf_workspace_create(model, &ws), NERAF_OK);
  std::vector<float> log(size_t(info.channels) * info.n_freq * info.n_frames);
  std::vector<float> rir(size_t(info.channels) * info.rir_length);
  const neraf_pose pose = {{0.5, 1.2, -0.5}, {2.0, 1.5, 1.0}, 90.0};
  for (int threads : {1, 2}) {
    ASSERT_EQ(neraf_workspace_set_threads(ws, threads), NERAF_OK);
    ASSERT_EQ(neraf_query_rir(model, ws, &pose, 0, rir.data(), rir.size()), NERAF_OK);  // warm
    armed = true;
    allocations = 0;
    const neraf_status a = neraf_query_log_stft(model, ws, &pose, 0, log.data(), log.size());
    const neraf_status b = neraf_query_rir(model, ws, &pose, 0, rir.data(), rir.size());
    armed = false;
    EXPECT_EQ(a, NERAF_OK);
    EXPECT_EQ(b, NERAF_OK);
    EXPECT_EQ(allocations, 0) << threads << " thread(s), " << neraf_model_compute(model);
  }
  neraf_workspace_free(ws);
  neraf_model_free(model);
  fs::remove_all(dir);
}

TEST(NoAllocation, QueriesAllocateNothing) {
  expect_queries_allocate_nothing(false);
  expect_queries_allocate_nothing(true);
}
