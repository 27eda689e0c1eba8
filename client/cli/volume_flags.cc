#include "client/cli/volume_flags.h"

#include "server/io/read_volume.h"

namespace vpm::cli {

void AddVolumeFlags(CLI::App* command, VolumeFlags* flags) {
  command
      ->add_option("--max-volume-bytes", flags->max_volume_bytes,
                   "bytes of the volume's values (2 per voxel for integer sources, 4 for "
                   "float), checked before reading; the default fits a 512 x 512 x 1,024 "
                   "int16 CT")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  command->add_flag("--progress", flags->progress,
                    "draw the progress bar of work over a second even when stderr is not a "
                    "terminal");
}

VolumeLimits ToVolumeLimits(const VolumeFlags& flags) {
  VolumeLimits limits;
  limits.max_volume_bytes = flags.max_volume_bytes;
  return limits;
}

Result<Volume> ReadVolumeForCli(std::string_view source, const VolumeFlags& flags,
                                const ProgressFn& progress) {
  return ReadVolume(source, ToVolumeLimits(flags), progress);
}

}  // namespace vpm::cli
