"""bHaptics Designer ``.tact`` patterns: :mod:`.project` parses the project object, :mod:`.render` renders its
tracks and effects to rows on the Player's tick, :mod:`.files` reads and writes ``.tact`` files as tracks."""
