//! Saving and loading impostors: placeholder replaced below.
