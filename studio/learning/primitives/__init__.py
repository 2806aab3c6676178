"""Dynamic movement primitives: fitting one to a demonstration, rolling it out, its policy files."""
