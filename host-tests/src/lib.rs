//! Host side of gough: wraps the core for the command-line tool and the tests.
