//! Per-frame uploads: the cloth surface, the colliders, the spheres and tubes
//! of surfaceless scenes, lines and particle discs.

use glam::Vec3;

use super::buffers::draw_count;
use super::geometry::{self, PointInstance};
use super::{Renderer, SPHERE_SKIN, SceneFrame, ViewOptions, markers, solids};

impl Renderer {
    /// The surface: indices only when the topology changes, vertices every frame.
    pub(super) fn upload_surface(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
        valid: &[bool],
        options: &ViewOptions,
    ) {
        let n = positions.len();
        let changed = match &self.topology {
            Some((tris, count)) => *count != n || tris.as_slice() != frame.triangles,
            None => true,
        };
        if changed {
            self.topology = Some((frame.triangles.to_vec(), n));
            self.edges = geometry::triangle_edges(frame.triangles);
            // The core winds its cloth so that the side facing the default camera is
            // clockwise; draw it the other way round so that side is the front.
            self.wound.clear();
            self.wound
                .extend(frame.triangles.iter().map(|&[a, b, c]| [a, c, b]));
            self.usable.clear();
            self.usable.extend(
                self.wound
                    .iter()
                    .filter(|t| t.iter().all(|&i| (i as usize) < n))
                    .flatten(),
            );
            let written = self.cloth_indices.write(device, queue, &self.usable);
            self.cloth_index_count = draw_count(written - written % 3);
        }
        let all_valid = valid.iter().all(|&v| v);
        self.mesh_visible = options.mesh && self.cloth_index_count > 0;
        if self.mesh_visible && self.cloth_index_count > 0 {
            let normals = geometry::vertex_normals(positions, &self.wound, valid);
            let mut mesh = std::mem::take(&mut self.scratch_mesh);
            geometry::cloth_vertices(positions, &normals, frame.uvs, options.textured, &mut mesh);
            if self.cloth_vertices.write(device, queue, &mesh) < mesh.len() {
                // Indices would reach past the vertices uploaded: no surface.
                self.mesh_visible = false;
            }
            self.scratch_mesh = mesh;
            if !all_valid {
                // Rare: drop triangles touching a non-finite particle this frame.
                let idx: Vec<u32> = self
                    .wound
                    .iter()
                    .filter(|t| geometry::usable_triangle(t, valid))
                    .flatten()
                    .copied()
                    .collect();
                let written = self.cloth_indices.write(device, queue, &idx);
                self.cloth_index_count = draw_count(written - written % 3);
                self.topology = None;
            }
        }
    }

    /// The sphere collider and the other colliders, at the frame's time.
    pub(super) fn upload_colliders(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
    ) {
        let mut extra = Vec::new();
        let mut extra_idx = Vec::new();
        if let Some((c, r)) = frame.sphere
            && let Some(c) = geometry::sanitize(c)
            && r.is_finite()
            && r > 0.0
        {
            // Drawn a little inside its collision radius: cloth resting on the sphere
            // has its particles on the surface and its flat triangles as chords
            // inside it, through which the full-size sphere would show.
            geometry::sphere_mesh(c, SPHERE_SKIN * r.min(1e4), &mut extra, &mut extra_idx);
        }
        for collider in frame.colliders {
            let skin = f64::from(SPHERE_SKIN);
            solids::push_collider(collider, frame.time, skin, &mut extra, &mut extra_idx);
        }
        let extra_index_count = if self.extra_vertices.write(device, queue, &extra) < extra.len() {
            0
        } else {
            let written = self.extra_indices.write(device, queue, &extra_idx);
            written - written % 3
        };
        self.extra_index_count = draw_count(extra_index_count);
    }

    /// Whether this frame draws its particles and springs as spheres and tubes:
    /// a scene without a surface, and not too many of them to build each frame.
    pub(super) fn uses_markers(frame: &SceneFrame<'_>) -> bool {
        frame.triangles.is_empty()
            && frame.positions.len().saturating_add(frame.lines.len()) <= markers::MAX_MARKERS
    }

    /// The spheres (particles) and tubes (springs) of a surfaceless scene.
    pub(super) fn upload_markers(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
        valid: &[bool],
        options: &ViewOptions,
    ) {
        self.marker_index_count = 0;
        if !Self::uses_markers(frame) {
            return;
        }
        let Some(r) = markers::sphere_radius(positions, valid, frame.lines) else {
            return;
        };
        let mut out = std::mem::take(&mut self.scratch_mesh);
        out.clear();
        let mut idx = Vec::new();
        if options.springs {
            let tube = r * markers::TUBE_FRACTION;
            for (k, &[a, b]) in frame.lines.iter().enumerate() {
                let (a, b) = (a as usize, b as usize);
                if !(valid.get(a).copied().unwrap_or(false)
                    && valid.get(b).copied().unwrap_or(false))
                {
                    continue;
                }
                let c = (frame.line_colors.get(k).copied())
                    .filter(|c| c.iter().all(|x| x.is_finite()))
                    .unwrap_or(geometry::WIRE_ALONE_COLOR);
                markers::push_tube(positions[a], positions[b], tube, c, &mut out, &mut idx);
            }
        }
        for (i, &p) in positions.iter().enumerate() {
            if !valid[i] {
                continue;
            }
            let pinned = options.pins && frame.pinned.get(i).copied().unwrap_or(false);
            let (color, scale) = if frame.highlight == Some(i) {
                (geometry::HIGHLIGHT_COLOR, 1.35)
            } else if pinned {
                (geometry::PIN_COLOR, 1.15)
            } else if options.particles {
                (geometry::PARTICLE_COLOR, 1.0)
            } else {
                continue;
            };
            markers::push_sphere(p, r * scale, color, &mut out, &mut idx);
        }
        if self.marker_vertices.write(device, queue, &out) == out.len() {
            let written = self.marker_indices.write(device, queue, &idx);
            self.marker_index_count = draw_count(written - written % 3);
        }
        self.scratch_mesh = out;
    }

    /// Lines: springs, then wireframe.
    pub(super) fn upload_lines(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
        valid: &[bool],
        options: &ViewOptions,
    ) {
        let mut lines = std::mem::take(&mut self.scratch_lines);
        lines.clear();
        if options.springs && !Self::uses_markers(frame) {
            let colors = frame.line_colors;
            geometry::push_lines(
                positions,
                valid,
                frame.lines,
                |k| colors.get(k).copied().unwrap_or(geometry::WIRE_COLOR),
                &mut lines,
            );
        }
        if options.wireframe {
            // Dark over the lit surface, light on the background without it.
            let color = match options.mesh {
                true => geometry::WIRE_COLOR,
                false => geometry::WIRE_ALONE_COLOR,
            };
            geometry::push_lines(positions, valid, &self.edges, |_| color, &mut lines);
        }
        self.push_ghost(frame, &mut lines);
        self.lines.write(device, queue, &lines);
        self.scratch_lines = lines;
    }

    /// The live reference's ghost: the cloth's edges (a surfaceless scene's
    /// springs) between the reference's positions, when it has one per particle.
    fn push_ghost(&self, frame: &SceneFrame<'_>, lines: &mut Vec<geometry::LineVertex>) {
        if frame.ghost.is_empty() || frame.ghost.len() != frame.positions.len() {
            return;
        }
        let (mut ghost, mut valid) = (Vec::new(), Vec::new());
        geometry::sanitize_all(frame.ghost, &mut ghost, &mut valid);
        let edges = match frame.triangles.is_empty() {
            true => frame.lines,
            false => &self.edges,
        };
        let color = |_| geometry::GHOST_COLOR;
        geometry::push_lines(&ghost, &valid, edges, color, lines);
    }

    /// Points: free particles, then pins and the highlight on top.
    pub(super) fn upload_points(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        frame: &SceneFrame<'_>,
        positions: &[Vec3],
        valid: &[bool],
        options: &ViewOptions,
    ) {
        let mut points = std::mem::take(&mut self.scratch_points);
        points.clear();
        if Self::uses_markers(frame) {
            // The particles are spheres.
            self.point_count = 0;
            self.scratch_points = points;
            return;
        }
        let size = options.particle_px.clamp(1.0, 64.0);
        for (i, p) in positions.iter().enumerate() {
            if !valid[i] {
                continue;
            }
            let pinned = frame.pinned.get(i).copied().unwrap_or(false);
            let highlighted = frame.highlight == Some(i);
            let (color, size) = if highlighted && pinned && options.pins {
                (geometry::PIN_COLOR, size * 1.6 + 2.0)
            } else if highlighted {
                (geometry::HIGHLIGHT_COLOR, size * 1.6 + 2.0)
            } else if pinned && options.pins {
                (geometry::PIN_COLOR, size * 1.4 + 1.0)
            } else if options.particles {
                (geometry::PARTICLE_COLOR, size)
            } else {
                continue;
            };
            points.push(PointInstance {
                position: p.to_array(),
                size,
                color,
            });
        }
        // Draw order = depth ties: later instances win, so put highlights last.
        points.sort_by(|a, b| a.size.total_cmp(&b.size));
        self.point_count = draw_count(self.points.write(device, queue, &points));
        self.scratch_points = points;
    }
}
