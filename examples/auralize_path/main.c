/* auralize_path: renders what a listener hears walking along a straight line, with an exported
 * neraf model (MODEL.nrf) and the C API of neraf_rt.
 *
 *   auralize_path MODEL.nrf DRY.wav OUT.wav --source X Y Z --from X Y Z --to X Y Z
 *                 [--yaw DEG] [--block N] [--update N] [--pcm16]
 *
 * DRY.wav: mono, 16-bit PCM or 32-bit float, at the model's sample rate. The microphone moves at
 * constant speed from --from to --to over the dry signal's duration (positions in metres in the
 * dataset's frame, as `neraf render rir`); the source stays at --source; --yaw is the heading.
 * Every --update samples (default 2048) the stream gets the pose of that moment and crossfades
 * to its RIR; neraf_stream_wait makes the output independent of timing (offline rendering).
 * OUT.wav gets the model's channels (binaural for SoundSpaces), 32-bit float or 16-bit PCM, and
 * the reverberation tail after the dry signal ends. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <neraf/neraf_rt.h>

typedef struct {
  int sample_rate;
  int channels;
  size_t frames;
  float* data; /* interleaved [frames][channels] */
} Audio;

static uint32_t le32(const unsigned char* p) {
  return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint16_t le16(const unsigned char* p) { return (uint16_t)(p[0] | p[1] << 8); }

/* A minimal RIFF/WAVE reader: PCM 16-bit or IEEE float 32-bit (plain or WAVE_FORMAT_EXTENSIBLE).
 * Returns 0 and fills *a, or prints why not and returns 1. */
static int read_wav(const char* path, Audio* a) {
  FILE* f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "%s: cannot open\n", path);
    return 1;
  }
  unsigned char h[12], ch[8], fmt[40];
  int format = 0, bits = 0, have_fmt = 0;
  memset(a, 0, sizeof *a);
  if (fread(h, 1, 12, f) != 12 || memcmp(h, "RIFF", 4) != 0 || memcmp(h + 8, "WAVE", 4) != 0) {
    fprintf(stderr, "%s: not a WAV file\n", path);
    fclose(f);
    return 1;
  }
  while (fread(ch, 1, 8, f) == 8) {
    const uint32_t size = le32(ch + 4);
    if (memcmp(ch, "fmt ", 4) == 0 && size >= 16 && size <= sizeof fmt) {
      if (fread(fmt, 1, size, f) != size) break;
      format = le16(fmt);
      a->channels = le16(fmt + 2);
      a->sample_rate = (int)le32(fmt + 4);
      bits = le16(fmt + 14);
      if (format == 0xFFFE && size >= 26) format = le16(fmt + 24); /* the sub-format GUID */
      have_fmt = 1;
    } else if (memcmp(ch, "data", 4) == 0 && have_fmt) {
      if (!((format == 1 && bits == 16) || (format == 3 && bits == 32)) || a->channels < 1) {
        fprintf(stderr, "%s: only 16-bit PCM and 32-bit float WAV files are supported\n", path);
        break;
      }
      const size_t bytes = (size_t)bits / 8;
      a->frames = size / (bytes * (size_t)a->channels);
      const size_t n = a->frames * (size_t)a->channels;
      unsigned char* raw = malloc(n * bytes + 1);
      a->data = malloc(sizeof(float) * (n + 1));
      if (!raw || !a->data || fread(raw, bytes, n, f) != n) {
        fprintf(stderr, "%s: truncated or out of memory\n", path);
        free(raw);
        break;
      }
      for (size_t i = 0; i < n; ++i) {
        if (format == 1) {
          a->data[i] = (float)(int16_t)le16(raw + 2 * i) / 32768.0f;
        } else {
          const uint32_t u = le32(raw + 4 * i);
          memcpy(&a->data[i], &u, 4);
        }
      }
      free(raw);
      fclose(f);
      return 0;
    } else {
      if (fseek(f, (long)size + (size & 1), SEEK_CUR) != 0) break; /* chunks are word-aligned */
    }
  }
  fprintf(stderr, "%s: no usable fmt/data chunks\n", path);
  free(a->data);
  a->data = NULL;
  fclose(f);
  return 1;
}

static void put32(FILE* f, uint32_t v) {
  const unsigned char b[4] = {v & 255, (v >> 8) & 255, (v >> 16) & 255, (v >> 24) & 255};
  fwrite(b, 1, 4, f);
}
static void put16(FILE* f, uint16_t v) {
  const unsigned char b[2] = {v & 255, v >> 8};
  fwrite(b, 1, 2, f);
}

/* Writes interleaved samples as 32-bit float (pcm16 = 0) or 16-bit PCM (clipped). */
static int write_wav(const char* path, const Audio* a, int pcm16) {
  FILE* f = fopen(path, "wb");
  if (!f) {
    fprintf(stderr, "%s: cannot create\n", path);
    return 1;
  }
  const uint32_t bytes = pcm16 ? 2 : 4;
  const uint32_t data = (uint32_t)(a->frames * (size_t)a->channels * bytes);
  fwrite("RIFF", 1, 4, f);
  put32(f, 36 + data);
  fwrite("WAVEfmt ", 1, 8, f);
  put32(f, 16);
  put16(f, pcm16 ? 1 : 3);
  put16(f, (uint16_t)a->channels);
  put32(f, (uint32_t)a->sample_rate);
  put32(f, (uint32_t)a->sample_rate * (uint32_t)a->channels * bytes);
  put16(f, (uint16_t)(a->channels * bytes));
  put16(f, (uint16_t)(8 * bytes));
  fwrite("data", 1, 4, f);
  put32(f, data);
  for (size_t i = 0; i < a->frames * (size_t)a->channels; ++i) {
    if (pcm16) {
      float v = a->data[i] * 32767.0f;
      v = v > 32767.0f ? 32767.0f : (v < -32768.0f ? -32768.0f : v);
      put16(f, (uint16_t)(int16_t)lrintf(v));
    } else {
      uint32_t u;
      memcpy(&u, &a->data[i], 4);
      put32(f, u);
    }
  }
  const int failed = ferror(f);
  if (fclose(f) != 0 || failed) {
    fprintf(stderr, "%s: write failed\n", path);
    return 1;
  }
  return 0;
}

static int parse_vec3(char** argv, int i, int argc, double v[3]) {
  if (i + 3 >= argc) return 0;
  for (int k = 0; k < 3; ++k) {
    char* end;
    v[k] = strtod(argv[i + 1 + k], &end);
    if (*end != '\0') return 0;
  }
  return 1;
}

static int usage(const char* argv0) {
  fprintf(stderr,
          "usage: %s MODEL.nrf DRY.wav OUT.wav --source X Y Z --from X Y Z --to X Y Z\n"
          "       [--yaw DEG] [--block N] [--update N] [--pcm16]\n",
          argv0);
  return 2;
}

/* Prints the failing call's message and returns 1. */
static int report(neraf_status s, const char* what) {
  fprintf(stderr, "%s: %s (%s)\n", what, neraf_last_error(), neraf_status_string(s));
  return 1;
}

int main(int argc, char** argv) {
  if (argc < 4) return usage(argv[0]);
  double source[3], from[3], to[3], yaw = 0.0;
  int have = 0, block = 256, update = 2048, pcm16 = 0;
  for (int i = 4; i < argc; ++i) {
    if (strcmp(argv[i], "--source") == 0 && parse_vec3(argv, i, argc, source)) {
      have |= 1, i += 3;
    } else if (strcmp(argv[i], "--from") == 0 && parse_vec3(argv, i, argc, from)) {
      have |= 2, i += 3;
    } else if (strcmp(argv[i], "--to") == 0 && parse_vec3(argv, i, argc, to)) {
      have |= 4, i += 3;
    } else if (strcmp(argv[i], "--yaw") == 0 && i + 1 < argc) {
      yaw = atof(argv[++i]);
    } else if (strcmp(argv[i], "--block") == 0 && i + 1 < argc) {
      block = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--update") == 0 && i + 1 < argc) {
      update = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--pcm16") == 0) {
      pcm16 = 1;
    } else {
      return usage(argv[0]);
    }
  }
  if (have != 7 || block <= 0 || update <= 0) return usage(argv[0]);

  neraf_model* model = NULL;
  neraf_status s = neraf_model_load(argv[1], &model);
  if (s != NERAF_OK) return report(s, "load");
  neraf_model_info info;
  neraf_model_get_info(model, &info);

  Audio dry;
  if (read_wav(argv[2], &dry) != 0) return 1;
  if (dry.channels != 1 || dry.sample_rate != info.sample_rate) {
    fprintf(stderr, "%s: need mono at %d Hz (the model's rate), got %d channel(s) at %d Hz\n",
            argv[2], info.sample_rate, dry.channels, dry.sample_rate);
    return 1;
  }

  neraf_stream* stream = NULL;
  s = neraf_stream_create(model, 0, block, 0, &stream);
  if (s != NERAF_OK) return report(s, "stream");

  /* The dry signal plus the RIR's tail, in whole blocks. */
  const int C = info.channels;
  const size_t total = dry.frames + (size_t)info.rir_length;
  const size_t n_blocks = (total + (size_t)block - 1) / (size_t)block;
  Audio wet = {info.sample_rate, C, n_blocks * (size_t)block, NULL};
  wet.data = calloc(wet.frames * (size_t)C, sizeof(float));
  float* in = calloc((size_t)block, sizeof(float));
  float* out = calloc((size_t)block * (size_t)C, sizeof(float));
  if (!wet.data || !in || !out) {
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  size_t next_update = 0;
  for (size_t b = 0; b < n_blocks; ++b) {
    const size_t start = b * (size_t)block;
    if (start >= next_update && start < dry.frames) {
      /* The pose at this moment of the walk. */
      const double a = dry.frames > 1 ? (double)start / (double)(dry.frames - 1) : 0.0;
      neraf_pose pose;
      for (int k = 0; k < 3; ++k) {
        pose.mic[k] = from[k] + a * (to[k] - from[k]);
        pose.source[k] = source[k];
      }
      pose.yaw_deg = yaw;
      s = neraf_stream_set_pose(stream, &pose, 0);
      if (s != NERAF_OK) return report(s, "pose");
      s = neraf_stream_wait(stream, 10000);
      if (s != NERAF_OK) return report(s, "wait");
      next_update += (size_t)update;
    }
    for (int i = 0; i < block; ++i)
      in[i] = start + (size_t)i < dry.frames ? dry.data[start + (size_t)i] : 0.0f;
    s = neraf_stream_process(stream, in, out);
    if (s != NERAF_OK) return report(s, "process");
    for (int c = 0; c < C; ++c) /* planar [C, block] → interleaved */
      for (int i = 0; i < block; ++i)
        wet.data[(start + (size_t)i) * (size_t)C + (size_t)c] = out[(size_t)(c * block + i)];
  }
  wet.frames = total;
  const int rc = write_wav(argv[3], &wet, pcm16);
  printf("%s: %zu samples x %d channels, %zu pose updates\n", argv[3], wet.frames, C,
         (dry.frames + (size_t)update - 1) / (size_t)update);

  free(in);
  free(out);
  free(wet.data);
  free(dry.data);
  neraf_stream_free(stream);
  neraf_model_free(model);
  return rc;
}
