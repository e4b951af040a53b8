//! The shapes' distances against geometry worked by hand, and the contact law's
//! push and friction against their definitions.

use glam::{DQuat, DVec3};

use super::mesh::closest_on_triangle;
use super::*;
