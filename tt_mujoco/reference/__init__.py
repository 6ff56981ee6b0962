"""What the vehicle should do: reference paths, tracking targets, path feedback."""
