/* neraf_rt: the real-time runtime of a trained neraf acoustic field (C ABI, no LibTorch).
 *
 * A model file (MODEL.nrf, written by `neraf export`) holds the acoustic field with the scene
 * feature folded in, its energy calibration and audio configuration. Load it once, then query
 * RIRs at any pose from any number of threads (one workspace per thread), or stream dry audio
 * through a partitioned convolver whose RIR follows a moving listener.
 *
 *   neraf_model* model;
 *   if (neraf_model_load("room.nrf", &model) != NERAF_OK) {
 *     fprintf(stderr, "%s\n", neraf_last_error());
 *     return 1;
 *   }
 *   neraf_model_info info;
 *   neraf_model_get_info(model, &info);
 *   neraf_workspace* ws;
 *   neraf_workspace_create(model, &ws);
 *   neraf_pose pose = {{1.0, 1.5, 2.0}, {3.0, 1.5, 0.5}, 90.0};
 *   float* rir = malloc(sizeof(float) * info.channels * info.rir_length);
 *   neraf_query_rir(model, ws, &pose, 0, rir, (size_t)info.channels * info.rir_length);
 *   ...
 *   neraf_workspace_free(ws);
 *   neraf_model_free(model);
 *
 * Conventions: positions in metres in the dataset's own frame (as `neraf render rir --mic/--src`:
 * SoundSpaces: y up, a points.txt row (x, y, z) is (x, z, -y); RAF as written); yaw in degrees
 * (the receiver heading for SoundSpaces, the source yaw for RAF). Arrays are row-major; a
 * multi-channel signal is planar: channel c occupies out[c * length .. (c + 1) * length).
 *
 * Errors: every function returns a neraf_status; on failure neraf_last_error() gives a one-line
 * message (per thread, valid until the thread's next failing call). No function aborts, throws
 * or prints.
 *
 * Threads: a neraf_model is immutable after load and may be shared by any number of threads; a
 * neraf_workspace belongs to one thread at a time. neraf_stream_process is real-time safe (no
 * allocation, no locks, no I/O); the other neraf_stream_* functions are called from one control
 * thread. */
#ifndef NERAF_NERAF_RT_H
#define NERAF_NERAF_RT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(NERAF_RT_BUILD) && defined(__GNUC__)
#define NERAF_RT_API __attribute__((visibility("default")))
#else
#define NERAF_RT_API
#endif

#define NERAF_RT_VERSION_MAJOR 0
#define NERAF_RT_VERSION_MINOR 1

typedef enum neraf_status {
  NERAF_OK = 0,
  NERAF_ERR_INVALID_ARGUMENT = 1, /* null pointer, zero or absurd size, unknown flag */
  NERAF_ERR_IO = 2,               /* the file cannot be opened or read */
  NERAF_ERR_FORMAT = 3,           /* not a neraf model, truncated, or checksum mismatch */
  NERAF_ERR_VERSION = 4,          /* written by a newer neraf (format version too high) */
  NERAF_ERR_NOT_FINITE = 5,       /* a NaN or infinite coordinate */
  NERAF_ERR_OUTSIDE = 6,          /* pose outside the training box (see NERAF_ALLOW_OUTSIDE) */
  NERAF_ERR_BUFFER_TOO_SMALL = 7, /* the output capacity is below what the query writes */
  NERAF_ERR_OUT_OF_MEMORY = 8,
  NERAF_ERR_INTERNAL = 9
} neraf_status;

typedef struct neraf_model neraf_model;
typedef struct neraf_workspace neraf_workspace;
typedef struct neraf_stream neraf_stream;

typedef struct neraf_pose {
  double mic[3];    /* microphone (listener) position, metres */
  double source[3]; /* source position, metres */
  double yaw_deg;   /* heading, degrees */
} neraf_pose;

typedef struct neraf_model_info {
  uint32_t format_version; /* the file's format: 1, or 2 for a shorter scene of a multi-scene run */
  int layout;         /* 0 SoundSpaces (binaural), 1 RAF (mono) */
  int sample_rate;    /* Hz */
  int channels;       /* C */
  int n_freq;         /* F: frequency bins of the log-STFT */
  int n_frames;       /* T: time frames of the log-STFT */
  int n_fft, win_length, hop_length;
  int rir_length;     /* samples per channel of neraf_query_rir's waveform */
  double box_min[3];  /* the training microphone/source box, metres */
  double box_max[3];
  char neraf_version[32]; /* the neraf that wrote the file, NUL-terminated */
} neraf_model_info;

/* Query flags. */
#define NERAF_ALLOW_OUTSIDE 1u /* accept poses outside the training box (results then meaningless) */

NERAF_RT_API const char* neraf_last_error(void);
NERAF_RT_API const char* neraf_status_string(neraf_status status);

/* Model. */
NERAF_RT_API neraf_status neraf_model_load(const char* path, neraf_model** out);
/* Load flags. A model exported in bfloat16 (`neraf export --precision bf16`) runs its trunk and
 * heads in bfloat16 where the CPU can: on AMX-BF16 tiles (Intel Sapphire Rapids and later:
 * several times faster), else with AVX512-BF16 (Intel Cooper Lake, AMD Zen 4 and later);
 * activations rounded to bfloat16 as in training, ~1e-2 from the float32 result in
 * log-magnitude. Elsewhere it runs in float32 with its bfloat16-rounded weights. */
#define NERAF_LOAD_FLOAT32 1u /* compute in float32 even where bfloat16 is available */
NERAF_RT_API neraf_status neraf_model_load_ex(const char* path, unsigned flags, neraf_model** out);
/* What the model's trunk and heads compute in: "float32", "bfloat16-amx" or "bfloat16-avx512"
 * (static storage). */
NERAF_RT_API const char* neraf_model_compute(const neraf_model* model);
NERAF_RT_API void neraf_model_free(neraf_model* model); /* NULL is a no-op */
NERAF_RT_API neraf_status neraf_model_get_info(const neraf_model* model, neraf_model_info* out);

/* Workspace: every buffer a query needs, allocated here so queries do not allocate. */
NERAF_RT_API neraf_status neraf_workspace_create(const neraf_model* model, neraf_workspace** out);
NERAF_RT_API void neraf_workspace_free(neraf_workspace* workspace);
/* Griffin-Lim of neraf_query_rir: iterations (default 32) and seed of the initial phases
 * (default 0), as `neraf render rir`. */
NERAF_RT_API neraf_status neraf_workspace_set_griffin_lim(neraf_workspace* workspace,
                                                          int iterations, uint64_t seed);
/* Threads a query of this workspace uses: the calling thread plus threads - 1 helpers started
 * here, which take whole channels (head, calibration, Griffin-Lim) and half the columns of large
 * layers. 0 = automatic (one per channel, at most the hardware's; the default), 1 = the calling
 * thread only (e.g. when many workspaces already query in parallel). Results agree to float
 * rounding (bit for bit on AMX and in Griffin-Lim). A multi-threaded BLAS keeps its own threads
 * and then does the float32 products unsplit; for steady latency run OpenBLAS on one thread
 * (OMP_NUM_THREADS=1 or OPENBLAS_NUM_THREADS=1): its idle workers spin on the cores the helpers
 * need. */
NERAF_RT_API neraf_status neraf_workspace_set_threads(neraf_workspace* workspace, int threads);

/* Queries. `capacity` is the number of floats `out` holds. */
/* Predicted log(|STFT| + 1e-3), energy calibration applied: [C, F, T], capacity >= C*F*T. */
NERAF_RT_API neraf_status neraf_query_log_stft(const neraf_model* model,
                                               neraf_workspace* workspace, const neraf_pose* pose,
                                               unsigned flags, float* out, size_t capacity);
/* The waveform (Griffin-Lim of the predicted magnitudes): planar [C, rir_length]. */
NERAF_RT_API neraf_status neraf_query_rir(const neraf_model* model, neraf_workspace* workspace,
                                          const neraf_pose* pose, unsigned flags, float* out,
                                          size_t capacity);

/* Streaming auralization: mono dry input, C output channels, uniformly partitioned overlap-save
 * convolution with `block_size` samples per call, a crossfade of one block when the RIR changes.
 * model may be NULL (then only neraf_stream_set_rir is available; channels and max_rir_length
 * must be given); with a model, 0 for channels / max_rir_length means the model's (channels, if
 * given, must equal the model's; a max_rir_length below the model's rir_length truncates its
 * RIRs). Limits: block_size 16 to 16384 (any integer; the FFT size is 2 * block_size),
 * channels 1 to 16, max_rir_length 1 to 11520000 samples (60 s at 192 kHz). Allocates everything
 * here (four RIR slots of about 8 bytes per RIR sample and channel each: 3 MB for 1 s binaural
 * at 48 kHz; the FFT plans, measured once per block size: milliseconds to a second)
 * and starts the stream's worker thread; with a model, its workspace runs single-threaded
 * (neraf_workspace_set_threads 1), so the worker never takes more than one core from the audio
 * thread. */
NERAF_RT_API neraf_status neraf_stream_create(const neraf_model* model, int channels,
                                              int block_size, size_t max_rir_length,
                                              neraf_stream** out);
/* Joins the worker (after the query in progress, if any; a pending one is dropped). NULL is a
 * no-op. */
NERAF_RT_API void neraf_stream_free(neraf_stream* stream);
/* A new pose: validated here (NERAF_ERR_NOT_FINITE, NERAF_ERR_OUTSIDE as neraf_query_rir), its
 * RIR computed on the stream's worker thread and handed to the audio thread without locks when
 * ready. Latest wins: a newer set_pose or set_rir replaces a request the worker has not started.
 * NERAF_ERR_INVALID_ARGUMENT on a stream without a model. */
NERAF_RT_API neraf_status neraf_stream_set_pose(neraf_stream* stream, const neraf_pose* pose,
                                                unsigned flags);
/* A given RIR (planar [channels, length], channels the stream's, 1 <= length <= max_rir_length,
 * finite values), handed over as a pose's: copied here (rir may be reused on return), prepared
 * on the worker thread. */
NERAF_RT_API neraf_status neraf_stream_set_rir(neraf_stream* stream, const float* rir,
                                               int channels, size_t length);
/* Blocks until the RIR of the latest set_pose / set_rir is computed and published, so that the
 * next neraf_stream_process call starts the crossfade to it; NERAF_ERR_INTERNAL after timeout_ms
 * (>= 0; 0 polls). If that request's query failed on the worker, returns its status and message
 * (the previous RIR then stays in use). NERAF_OK at once when nothing was requested.
 * For offline rendering, where the output must not depend on timing. */
NERAF_RT_API neraf_status neraf_stream_wait(neraf_stream* stream, int timeout_ms);
/* Real-time safe (no allocation, no locks, no system calls; one thread at a time). in:
 * block_size mono samples; out: planar [channels, block_size]; out may overlap in. Before any RIR
 * is set the output is silence; a RIR published before the first call applies from the first
 * sample, one published later fades in over one block (from silence, or from the previous RIR).
 * Denormals are flushed to zero during the call (the caller's floating-point mode is restored). */
NERAF_RT_API neraf_status neraf_stream_process(neraf_stream* stream, const float* in, float* out);

#ifdef __cplusplus
}
#endif

#endif /* NERAF_NERAF_RT_H */
