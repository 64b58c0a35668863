//! Placeholder for the real-data diagnosis (filled below).
