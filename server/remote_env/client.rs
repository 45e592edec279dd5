//! [`RemoteEnv`]: an environment in another process or on another machine, as an `Env` like the
//! built-in tasks. A blocking TCP client (std only) on the calling thread, which is the
//! session's or the CLI's own: no async runtime. Every read has a deadline; the first fault
//! breaks the connection for good and every later call returns it, so a run that meets one
//! stops with the reason.

use std::net::{TcpStream, ToSocketAddrs};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::description::{RemoteDescription, check};
use super::wire::{self, FrameHeader, PROTOCOL, Reply, Request, WireError};
use crate::sim::{
    Env, EnvFault, EnvSpec, Geometry, ImageFrame, MediaType, Outcome, RenderState, Step,
};

/// How long to wait for a connection, and for each answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timeouts {
    pub connect: Duration,
    /// The longest one request (a reset of a robot included) may take.
    pub request: Duration,
}

/// The default wait for each answer (a session's `env_timeout_s`).
pub const DEFAULT_REQUEST_TIMEOUT: Duration = Duration::from_secs(30);

impl Default for Timeouts {
    fn default() -> Self {
        Self {
            connect: Duration::from_secs(10),
            request: DEFAULT_REQUEST_TIMEOUT,
        }
    }
}

/// The `host:port` of a `tcp://host:port` URL.
pub fn parse_url(url: &str) -> Result<&str, EnvFault> {
    let address = url.strip_prefix("tcp://").ok_or_else(|| {
        EnvFault(format!(
            "env URL {url:?}: expected tcp://HOST:PORT (the env protocol runs over TCP)"
        ))
    })?;
    let address = address.trim_end_matches('/');
    let valid = address
        .rsplit_once(':')
        .is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok_and(|p| p > 0));
    if !valid {
        return Err(EnvFault(format!(
            "env URL {url:?}: expected tcp://HOST:PORT with a port in 1-65535"
        )));
    }
    Ok(address)
}

pub struct RemoteEnv {
    url: String,
    stream: TcpStream,
    timeouts: Timeouts,
    description: RemoteDescription,
    /// Ask for a frame with every reset and step (people are watching).
    frames: bool,
    obs: Vec<f32>,
    elapsed: u32,
    /// The episode ended: the next call must be a reset.
    ended: bool,
    frame: Option<ImageFrame>,
    predicates: u32,
    features: Vec<f64>,
    /// The action in the env's own units, reused.
    scaled: Vec<f64>,
    broken: Option<EnvFault>,
}

impl RemoteEnv {
    /// Connect to the env at `url` (`tcp://host:port`) and read its description.
    pub fn connect(url: &str, timeouts: Timeouts) -> Result<Self, EnvFault> {
        let address = parse_url(url)?;
        let unreachable = |e: String| EnvFault(format!("the env at {url} is unreachable: {e}"));
        let addrs: Vec<_> = address
            .to_socket_addrs()
            .map_err(|e| unreachable(e.to_string()))?
            .collect();
        let mut last = String::from("the host name has no address");
        let mut stream = None;
        for addr in addrs {
            match TcpStream::connect_timeout(&addr, timeouts.connect) {
                Ok(s) => {
                    stream = Some(s);
                    break;
                }
                Err(e) => last = e.to_string(),
            }
        }
        let stream = stream.ok_or_else(|| unreachable(last))?;
        // One small message each way per step: do not wait to fill a packet.
        stream
            .set_nodelay(true)
            .map_err(|e| unreachable(e.to_string()))?;
        stream
            .set_write_timeout(Some(timeouts.request))
            .map_err(|e| unreachable(e.to_string()))?;
        let mut env = Self {
            url: url.to_string(),
            stream,
            timeouts,
            description: placeholder(),
            frames: false,
            obs: Vec::new(),
            elapsed: 0,
            ended: true,
            frame: None,
            predicates: 0,
            features: Vec::new(),
            scaled: Vec::new(),
            broken: None,
        };
        let reply = env.call(&Request::Hello {
            protocol: PROTOCOL,
            client: concat!("dualrep ", env!("CARGO_PKG_VERSION")),
        })?;
        let description = match reply {
            Reply::Hello { protocol, env: d } if protocol == PROTOCOL => {
                check(&d).map_err(|e| env.fault(format!("its hello is not valid: {e}")))?
            }
            Reply::Hello { protocol, .. } => {
                return Err(env.fault(format!(
                    "it speaks protocol {protocol}; this dualrep speaks {PROTOCOL}"
                )));
            }
            other => return Err(env.unexpected("hello", &other)),
        };
        env.obs = vec![0.0; description.observation_dim()];
        env.scaled = vec![0.0; description.action_dim()];
        env.description = description;
        Ok(env)
    }

    pub fn url(&self) -> &str {
        &self.url
    }

    /// What the env declared.
    pub fn description(&self) -> &RemoteDescription {
        &self.description
    }

    /// Break the connection with `reason` (every later call returns it).
    fn fault(&mut self, reason: String) -> EnvFault {
        let fault = EnvFault(format!("the env at {}: {reason}", self.url));
        let _ = self.stream.shutdown(std::net::Shutdown::Both);
        self.broken = Some(fault.clone());
        fault
    }

    fn unexpected(&mut self, wanted: &str, got: &Reply) -> EnvFault {
        match got {
            Reply::Error { message } => self.fault(format!("it reported an error: {message}")),
            other => {
                let kind = match other {
                    Reply::Hello { .. } => "hello",
                    Reply::Reset(_) => "reset",
                    Reply::Step(_) => "step",
                    Reply::Close {} => "close",
                    Reply::Error { .. } => "error",
                };
                self.fault(format!("it answered a {wanted} with a {kind}"))
            }
        }
    }

    /// Send `request` and read its reply, within the request timeout.
    fn call(&mut self, request: &Request<'_>) -> Result<Reply, EnvFault> {
        if let Some(fault) = &self.broken {
            return Err(fault.clone());
        }
        let deadline = Instant::now() + self.timeouts.request;
        let result = wire::send(&mut self.stream, request)
            .and_then(|()| wire::receive(&mut self.stream, deadline));
        let body = result.map_err(|e| self.wire_fault(e))?;
        serde_json::from_slice::<Reply>(&body)
            .map_err(|e| self.fault(format!("it sent a malformed message ({e})")))
    }

    fn wire_fault(&mut self, e: WireError) -> EnvFault {
        let reason = match e {
            WireError::Timeout(_) => format!(
                "no answer within {:.1} s (the session's env_timeout_s)",
                self.timeouts.request.as_secs_f64()
            ),
            WireError::Closed => "it closed the connection (did it stop?)".into(),
            WireError::Io(e) => format!("the connection failed: {e}"),
            WireError::Malformed(what) => format!("it sent {what}"),
        };
        self.fault(reason)
    }

    /// Read the frame a reply announced (there must be one exactly when one was asked for).
    fn read_frame(&mut self, header: Option<FrameHeader>) -> Result<(), EnvFault> {
        self.frame = None;
        let Some(h) = header else {
            return if self.frames {
                Err(self.fault("a frame was asked for and none came".into()))
            } else {
                Ok(())
            };
        };
        let deadline = Instant::now() + self.timeouts.request;
        let bytes = wire::receive_frame(&mut self.stream, h.bytes, deadline)
            .map_err(|e| self.wire_fault(e))?;
        if !self.frames {
            return Err(self.fault("it sent a frame nobody asked for".into()));
        }
        let media_type = MediaType::from_format(&h.format).ok_or_else(|| {
            self.fault(format!("frame format {:?}: expected png or jpeg", h.format))
        })?;
        if !media_type.matches(&bytes) {
            return Err(self.fault(format!("its frame is not a {} file", h.format)));
        }
        self.frame = Some(ImageFrame {
            media_type,
            width: h.width,
            height: h.height,
            data: Arc::from(bytes),
        });
        Ok(())
    }

    /// Check and keep an observation.
    fn take_obs(&mut self, obs: &[f64]) -> Result<(), EnvFault> {
        if obs.len() != self.obs.len() {
            return Err(self.fault(format!(
                "an observation of {} entries (it declared {})",
                obs.len(),
                self.obs.len()
            )));
        }
        if let Some(i) = obs.iter().position(|v| !v.is_finite()) {
            return Err(self.fault(format!("observation entry {i} is {}", obs[i])));
        }
        for (o, &v) in self.obs.iter_mut().zip(obs) {
            *o = v as f32;
        }
        Ok(())
    }

    /// The bits of the predicates named in `holding`.
    fn take_holding(&mut self, holding: &[String]) -> Result<(), EnvFault> {
        let mut bits = 0u32;
        for name in holding {
            match self.description.predicate_bits.get(name) {
                Some(&bit) => bits |= 1 << bit,
                None => {
                    return Err(
                        self.fault(format!("predicate {name:?} holds, but it was not declared"))
                    );
                }
            }
        }
        self.predicates = bits;
        Ok(())
    }

    fn try_reset_inner(&mut self, seed: u64) -> Result<Vec<f32>, EnvFault> {
        let reply = self.call(&Request::Reset {
            seed,
            render: self.frames,
        })?;
        let r = match reply {
            Reply::Reset(r) => r,
            other => return Err(self.unexpected("reset", &other)),
        };
        self.read_frame(r.frame)?;
        self.take_obs(&r.obs)?;
        self.take_holding(&r.holding)?;
        self.features.clear();
        self.elapsed = 0;
        self.ended = false;
        Ok(self.obs.clone())
    }

    fn try_step_inner(&mut self, action: &[f32]) -> Result<Step, EnvFault> {
        if self.ended {
            return Err(EnvFault(format!(
                "the env at {}: stepped with no episode under way (reset first)",
                self.url
            )));
        }
        assert_eq!(action.len(), self.scaled.len(), "action size");
        let d = &self.description;
        for (i, (s, &a)) in self.scaled.iter_mut().zip(action).enumerate() {
            let unit = f64::from(a.clamp(-1.0, 1.0));
            *s = d.action_low[i] + (unit + 1.0) * 0.5 * (d.action_high[i] - d.action_low[i]);
        }
        let scaled = std::mem::take(&mut self.scaled);
        let reply = self.call(&Request::Step {
            action: &scaled,
            render: self.frames,
        });
        self.scaled = scaled;
        let r = match reply? {
            Reply::Step(r) => r,
            other => return Err(self.unexpected("step", &other)),
        };
        self.read_frame(r.frame)?;
        self.take_obs(&r.obs)?;
        self.take_holding(&r.holding)?;
        if !r.reward.is_finite() {
            return Err(self.fault(format!("a reward of {}", r.reward)));
        }
        match (r.features, self.description.features.len()) {
            (None, 0) => self.features.clear(),
            (Some(f), n) if f.len() == n && n > 0 && f.iter().all(|v| v.is_finite()) => {
                self.features = f;
            }
            (f, n) => {
                return Err(self.fault(format!("features {f:?} on a step (it declared {n})")));
            }
        }
        self.elapsed += 1;
        // The declared episode limit is enforced here too, as Gymnasium's TimeLimit would.
        let truncated = r.truncated
            || (!r.terminated && self.elapsed >= self.description.spec.max_episode_steps);
        let outcome = if r.terminated {
            Some(if r.success == Some(true) {
                Outcome::Success
            } else {
                Outcome::Failure
            })
        } else if truncated {
            Some(if r.success == Some(true) {
                Outcome::Success
            } else {
                Outcome::TimeLimit
            })
        } else {
            None
        };
        self.ended = outcome.is_some();
        Ok(Step {
            obs: self.obs.clone(),
            reward: r.reward as f32,
            terminated: r.terminated,
            truncated: truncated && !r.terminated,
            outcome,
        })
    }
}

/// The longest a goodbye waits for the env's `close` reply.
const CLOSE_WAIT: Duration = Duration::from_secs(2);

impl Drop for RemoteEnv {
    /// Say goodbye however the connection's user ends (a session that finished, stopped, was
    /// interrupted or failed elsewhere; a CLI run): `close`, and the env's `close` back, so that
    /// the env can let go of what the connection held (a robot can park, a factory's env can be
    /// closed) instead of guessing from a dropped socket. Best effort and brief: a broken
    /// connection gets none, and a slow env is not waited on for long.
    fn drop(&mut self) {
        if self.broken.is_some() {
            return;
        }
        let deadline = Instant::now() + self.timeouts.request.min(CLOSE_WAIT);
        if wire::send(&mut self.stream, &Request::Close).is_ok() {
            let _ = wire::receive(&mut self.stream, deadline);
        }
        let _ = self.stream.shutdown(std::net::Shutdown::Both);
    }
}

/// The description a connection has before its env's hello arrived.
fn placeholder() -> RemoteDescription {
    RemoteDescription {
        spec: EnvSpec {
            id: "",
            observation_space: crate::sim::BoxSpace::uniform(0, 0.0, 0.0),
            action_space: crate::sim::BoxSpace::uniform(0, -1.0, 1.0),
            observation_names: Vec::new(),
            action_names: Vec::new(),
            max_episode_steps: 1,
            control_hz: 1.0,
        },
        action_low: Vec::new(),
        action_high: Vec::new(),
        graph: crate::scene_graph::SceneGraph::Declared(&[]),
        predicate_bits: Default::default(),
        features: Vec::new(),
        render: false,
        deterministic: false,
    }
}

impl Env for RemoteEnv {
    fn spec(&self) -> &EnvSpec {
        &self.description.spec
    }

    fn reset(&mut self, seed: u64) -> Vec<f32> {
        self.try_reset(seed)
            .unwrap_or_else(|fault| panic!("{fault}"))
    }

    fn step(&mut self, action: &[f32]) -> Step {
        self.try_step(action)
            .unwrap_or_else(|fault| panic!("{fault}"))
    }

    fn observation(&self) -> Vec<f32> {
        self.obs.clone()
    }

    fn elapsed_steps(&self) -> u32 {
        self.elapsed
    }

    fn render(&self) -> RenderState {
        RenderState::Remote {
            frame: self.frame.clone(),
            observation: self.obs.clone(),
        }
    }

    fn geometry(&self) -> Geometry {
        Geometry::Remote {
            env: self.description.spec.id.to_string(),
            frame_size: self.frame.as_ref().map(|f| [f.width, f.height]),
        }
    }

    fn try_reset(&mut self, seed: u64) -> Result<Vec<f32>, EnvFault> {
        self.try_reset_inner(seed)
    }

    fn try_step(&mut self, action: &[f32]) -> Result<Step, EnvFault> {
        self.try_step_inner(action)
    }

    fn reported_predicates(&self) -> Option<u32> {
        Some(self.predicates)
    }

    fn reported_features(&self) -> Option<&[f64]> {
        (!self.description.features.is_empty()).then_some(self.features.as_slice())
    }

    /// Frames with every reset and step while on (and the env can render): for sessions people
    /// watch. Off by default.
    fn set_frames(&mut self, on: bool) {
        self.frames = on && self.description.render;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_are_tcp_host_and_port() {
        assert_eq!(parse_url("tcp://127.0.0.1:5555").unwrap(), "127.0.0.1:5555");
        assert_eq!(parse_url("tcp://robot.lab:80/").unwrap(), "robot.lab:80");
        for bad in [
            "http://x:1",
            "tcp://x",
            "tcp://:80",
            "tcp://x:0",
            "tcp://x:70000",
        ] {
            assert!(parse_url(bad).is_err(), "{bad}");
        }
    }
}

#[cfg(test)]
#[path = "client_tests.rs"]
mod fault_tests;
