//! The window: winit's event loop on the main thread, a wgpu surface, egui's input state and
//! the [`Viewer`] drawn each frame by [`Gfx`] (the same painting as offscreen). The render
//! worker and the editor wake the loop through an [`EventLoopProxy`]; nothing here waits for a
//! render.

use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context;
use winit::application::ApplicationHandler;
use winit::dpi::LogicalSize;
use winit::event::{StartCause, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop, EventLoopProxy};
use winit::window::{Window, WindowId};

use super::app::Viewer;
use super::gfx::Gfx;
use super::offscreen::ui_device;

/// What other threads tell the event loop.
#[derive(Clone, Debug, PartialEq)]
pub enum UserEvent {
    /// Something changed (a frame rendered, an edit, egui asked for a repaint): redraw.
    Wake,
    /// Open the window (again), if it is closed (`:window` in the editor).
    Open,
    /// Leave the event loop (the editor quit).
    Quit,
}

/// The event loop, or why there can be none (no display).
pub fn event_loop() -> anyhow::Result<EventLoop<UserEvent>> {
    EventLoop::<UserEvent>::with_user_event()
        .build()
        .map_err(|e| {
            let hint = if std::env::var_os("DISPLAY").is_none()
                && std::env::var_os("WAYLAND_DISPLAY").is_none()
            {
                " (neither DISPLAY nor WAYLAND_DISPLAY is set: run it on a desktop, or under \
             `xvfb-run -a` for a virtual display)"
            } else {
                ""
            };
            anyhow::anyhow!("cannot open a window: {e}{hint}")
        })
}

/// How the event loop behaves when its window closes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OnClose {
    /// `view`: closing the window ends the loop.
    Exit,
    /// `edit --window`: the loop waits (for `:window` or the editor quitting).
    Wait,
}

struct Shown {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    gfx: Gfx,
    egui: egui_winit::State,
}

/// The window's application state.
pub struct WindowApp {
    viewer: Viewer,
    ctx: egui::Context,
    instance: wgpu::Instance,
    shown: Option<Shown>,
    open: bool,
    on_close: OnClose,
    /// The error that ended the loop, if one did.
    pub error: Option<anyhow::Error>,
    /// Called when the window fails (e.g. no adapter) so the editor can say so.
    on_error: Option<Box<dyn Fn(String)>>,
    repaint_at: Option<Instant>,
    /// The window's inner size when it opens (logical pixels).
    size: LogicalSize<f64>,
}

impl std::fmt::Debug for WindowApp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WindowApp")
            .field("open", &self.open)
            .finish_non_exhaustive()
    }
}

/// A waker for the render worker and egui: it posts [`UserEvent::Wake`].
pub fn waker(proxy: EventLoopProxy<UserEvent>) -> Box<dyn Fn() + Send + Sync> {
    Box::new(move || {
        let _ = proxy.send_event(UserEvent::Wake);
    })
}

impl WindowApp {
    /// The application for `viewer`; `open` shows the window at once.
    pub fn new(
        event_loop: &EventLoop<UserEvent>,
        viewer: Viewer,
        open: bool,
        on_close: OnClose,
    ) -> WindowApp {
        let ctx = egui::Context::default();
        ctx.set_visuals(egui::Visuals::dark());
        let proxy = event_loop.create_proxy();
        ctx.set_request_repaint_callback(move |info| {
            if info.delay.is_zero() {
                let _ = proxy.send_event(UserEvent::Wake);
            }
        });
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        WindowApp {
            viewer,
            ctx,
            instance,
            shown: None,
            open,
            on_close,
            error: None,
            on_error: None,
            repaint_at: None,
            size: LogicalSize::new(1500.0, 820.0),
        }
    }

    /// Opens the window at `width × height` logical pixels.
    pub fn with_size(mut self, width: f64, height: f64) -> WindowApp {
        self.size = LogicalSize::new(width, height);
        self
    }

    /// Reports window failures through `f` (besides ending with them under [`OnClose::Exit`]).
    pub fn on_error(mut self, f: Box<dyn Fn(String)>) -> WindowApp {
        self.on_error = Some(f);
        self
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, e: anyhow::Error) {
        if let Some(f) = &self.on_error {
            f(format!("{e:#}"));
        }
        self.shown = None;
        self.open = false;
        match self.on_close {
            OnClose::Exit => {
                self.error = Some(e);
                event_loop.exit();
            }
            OnClose::Wait => {}
        }
    }

    fn create(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<Shown> {
        let attrs = Window::default_attributes()
            .with_title(format!("flarebench — {}", self.viewer.system().name))
            .with_inner_size(self.size);
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .context("cannot create the window")?,
        );
        let surface = self
            .instance
            .create_surface(Arc::clone(&window))
            .context("cannot draw into the window (no surface)")?;
        let (adapter, device, queue) = ui_device(&self.instance, Some(&surface))?;
        let caps = surface.get_capabilities(&adapter);
        // egui draws in gamma space into a non-sRGB target, in linear space into an sRGB one.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .context("the window's surface offers no format")?;
        let size = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::AutoVsync,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
        };
        surface.configure(&device, &config);
        let egui = egui_winit::State::new(
            self.ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        Ok(Shown {
            window,
            surface,
            config,
            gfx: Gfx::new(device, queue, format, false),
            egui,
        })
    }

    fn redraw(&mut self) {
        let Some(s) = &mut self.shown else { return };
        let input = s.egui.take_egui_input(&s.window);
        let viewer = &mut self.viewer;
        let output = self.ctx.run_ui(input, |ui| viewer.frame(ui));
        s.egui
            .handle_platform_output(&s.window, output.platform_output.clone());
        let delay = output
            .viewport_output
            .get(&egui::ViewportId::ROOT)
            .map_or(Duration::MAX, |v| v.repaint_delay);
        let frame = match s.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(f)
            | wgpu::CurrentSurfaceTexture::Suboptimal(f) => f,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                s.surface.configure(&s.gfx.device, &s.config);
                s.window.request_redraw();
                return;
            }
            _ => {
                s.window.request_redraw();
                return;
            }
        };
        let view = frame.texture.create_view(&Default::default());
        s.gfx
            .paint(&self.ctx, output, &view, [s.config.width, s.config.height]);
        s.window.pre_present_notify();
        s.gfx.queue.present(frame);
        self.repaint_at = if delay.is_zero() {
            s.window.request_redraw();
            None
        } else {
            Instant::now().checked_add(delay)
        };
    }
}

impl ApplicationHandler<UserEvent> for WindowApp {
    fn new_events(&mut self, _: &ActiveEventLoop, cause: StartCause) {
        if let StartCause::ResumeTimeReached { .. } = cause
            && let Some(s) = &self.shown
        {
            self.repaint_at = None;
            s.window.request_redraw();
        }
    }

    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.open && self.shown.is_none() {
            match self.create(event_loop) {
                Ok(s) => self.shown = Some(s),
                Err(e) => self.fail(event_loop, e),
            }
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, event: UserEvent) {
        match event {
            UserEvent::Wake => {
                if let Some(s) = &self.shown {
                    s.window.request_redraw();
                }
            }
            UserEvent::Open => {
                self.open = true;
                if self.shown.is_none() {
                    match self.create(event_loop) {
                        Ok(s) => self.shown = Some(s),
                        Err(e) => self.fail(event_loop, e),
                    }
                } else if let Some(s) = &self.shown {
                    s.window.focus_window();
                }
            }
            UserEvent::Quit => event_loop.exit(),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let Some(s) = &mut self.shown else { return };
        let response = s.egui.on_window_event(&s.window, &event);
        match event {
            WindowEvent::CloseRequested => {
                self.shown = None;
                self.open = false;
                if self.on_close == OnClose::Exit {
                    event_loop.exit();
                }
            }
            WindowEvent::Resized(size) => {
                s.config.width = size.width.max(1);
                s.config.height = size.height.max(1);
                s.surface.configure(&s.gfx.device, &s.config);
                s.window.request_redraw();
            }
            WindowEvent::RedrawRequested => self.redraw(),
            _ => {
                if response.repaint {
                    s.window.request_redraw();
                }
            }
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        event_loop.set_control_flow(match self.repaint_at {
            Some(t) => ControlFlow::WaitUntil(t),
            None => ControlFlow::Wait,
        });
    }
}

/// Runs `app` on `event_loop` until the window closes (or, with [`OnClose::Wait`], until
/// [`UserEvent::Quit`]).
pub fn run(event_loop: EventLoop<UserEvent>, app: &mut WindowApp) -> anyhow::Result<()> {
    event_loop
        .run_app(app)
        .context("the window's event loop failed")?;
    match app.error.take() {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
