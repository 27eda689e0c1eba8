// What the server's reader corrected or chose when it read a volume
// (VolumeInfo.notes: a gantry tilt resampled, uneven gaps, the series or
// stack taken from a folder of several), as one line for the page's message
// when the volume opens, so that the user knows what is shown; '' when the
// reader had nothing to say.
export function volumeNotesText(volume) {
  const notes = (volume?.notes ?? []).filter((n) => typeof n === 'string' && n);
  return notes.length ? `Read from ${volume.source}: ${notes.join('; ')}.` : '';
}
