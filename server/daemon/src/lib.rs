//! shiftd: the SHIFT daemon and its command-line front end.
